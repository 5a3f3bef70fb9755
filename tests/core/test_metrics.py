"""The metrics' lower bounds: exact where they say so, valid otherwise, and named."""

from __future__ import annotations

import json

import pytest

from swarmshape.core import metrics
from swarmshape.core.bounds import travel_steps
from swarmshape.core.metrics import run_metrics
from swarmshape.runs import run
from swarmshape.session import summary_line
from tests.conftest import grid_from, make_swarm
from tests.core.test_bounds import pair_costs, true_bottleneck, true_distance

SHAPE = grid_from("#####\n#...#\n#.###\n###..")


@pytest.mark.parametrize("agents", [None, 20])
def test_bounds_in_the_metrics_match_brute_force(agents):
    swarm = make_swarm(SHAPE, agents=agents, seed=3, strategy="optimal")
    run(swarm, max_steps=20_000)
    found = run_metrics(swarm)
    starts, targets = swarm.start_cell, swarm.world.targets
    longest = true_bottleneck(starts, targets)
    assert found["makespan_bound_cells"] == longest
    assert found["makespan_lower_bound"] == travel_steps(longest, swarm.params.limits)
    assert found["distance_lower_bound"] == true_distance(starts, targets)
    for name in ("makespan", "distance"):
        assert found[f"{name}_bound_method"] == "exact"
        assert found[f"{name}_bound_exact"] is True
        assert found["groups"][0][f"{name}_bound_method"] == "exact"
    assert found["makespan_ratio"] >= 1.0 and found["distance_ratio"] >= 1.0
    assert json.loads(json.dumps(found)) == found
    assert summary_line(found).endswith("x the makespan lower bound (exact)")


def test_without_time_for_flows_the_metrics_say_which_bound_stands_in(monkeypatch):
    swarm = make_swarm(SHAPE, agents=20, seed=3, strategy="optimal")
    run(swarm, max_steps=20_000)
    monkeypatch.setattr(metrics, "BOUND_SECONDS", 0.0)
    found = run_metrics(swarm)
    starts, targets = swarm.start_cell, swarm.world.targets
    nearest = int(pair_costs(starts, targets).min(axis=1).max())
    assert found["makespan_bound_method"] == "hall"
    assert found["makespan_bound_exact"] is False
    assert nearest <= found["makespan_bound_cells"] <= true_bottleneck(starts, targets)
    assert found["distance_bound_method"] == "dual" and found["distance_bound_exact"] is False
    assert found["distance_lower_bound"] <= true_distance(starts, targets)
    assert "makespan lower bound (hall bound, not proved exact)" in summary_line(found)

"""The metrics' lower bounds: exact where they say so, valid otherwise, and named; the paper's
rates (Sun et al. 2023) as their definitions give them."""

from __future__ import annotations

import json

import numpy as np
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


def test_entering_and_uniformity_count_the_robots_on_the_shape_as_the_paper_defines_them():
    swarm = make_swarm(SHAPE, agents=20, seed=3, strategy="optimal")
    targets = swarm.world.targets
    off = np.argwhere(~swarm.world.mask(targets))
    picked = targets[::2]  # some alone, some side by side
    far = np.linalg.norm(off - targets.mean(axis=0), axis=1).argsort()[len(picked) - 20 :]
    cells = np.concatenate([picked, off[far]])
    swarm.cell[:] = cells
    swarm.offset[:] = 0.0
    on = swarm.world.mask(targets)[cells[:, 0], cells[:, 1]]
    gaps = np.linalg.norm(cells[:, None] - cells[None], axis=2) + np.diag(np.full(20, np.inf))
    radius = swarm.params.senses.radius
    nearest = np.minimum(gaps[on].min(axis=1), radius)
    assert metrics.entering(swarm) == round(len(picked) / 20, metrics.DIGITS)
    assert metrics.uniformity(swarm) == pytest.approx(nearest.var(), abs=1e-6)
    assert metrics.uniformity(swarm) > 0


def test_a_formed_shape_with_spares_has_every_target_filled_and_even_spacing():
    swarm = make_swarm(SHAPE, agents=20, seed=3, strategy="optimal")
    run(swarm, max_steps=20_000)
    found = run_metrics(swarm)
    assert found["coverage"] == 1.0
    assert found["entering"] == round(len(swarm.world.targets) / 20, metrics.DIGITS)
    assert found["uniformity"] == 0.0
    assert found["groups"][0]["entering"] == found["entering"]

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.spatial.distance import cdist

from swarmshape.core import assignment
from swarmshape.core.metrics import run_metrics
from swarmshape.runs import run
from tests.conftest import grid_from, make_swarm

MATCHERS = [assignment.optimal, assignment.greedy, assignment.random_assignment]


def scene(agents: int, targets: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    a = np.floor(rng.random((agents, 2)) * 80)
    t = np.floor(rng.random((targets, 2)) * 20 + 30)
    return a, t, rng


@pytest.mark.parametrize("match", MATCHERS)
@pytest.mark.parametrize("shape", [(30, 30), (40, 25)])
def test_every_target_gets_its_own_agent(match, shape):
    a, t, rng = scene(*shape)
    chosen = match(a, t, rng)
    assert len(chosen) == len(t)
    assert len(set(chosen.tolist())) == len(t)
    assert chosen.min() >= 0 and chosen.max() < len(a)


def squared_total(a, t, chosen):
    return float(((a[chosen] - t) ** 2).sum())


def test_optimal_is_exact_on_small_cases():
    a, t, rng = scene(6, 5)
    best = min(squared_total(a, t, np.array(p)) for p in itertools.permutations(range(6), 5))
    assert squared_total(a, t, assignment.optimal(a, t, rng)) == pytest.approx(best)


@pytest.mark.parametrize("spare", [0, 200])
def test_bisection_stays_within_5_percent_of_exact(monkeypatch, spare):
    rng = np.random.default_rng(3)
    t = np.argwhere(np.ones((25, 40))) + 40.0  # a 1,000-cell block in the middle
    a = np.floor(rng.random((1000 + spare, 2)) * 120)
    exact = squared_total(a, t, assignment.optimal(a, t, rng))
    monkeypatch.setattr(assignment, "EXACT_LIMIT", 0)
    approximate = squared_total(a, t, assignment.optimal(a, t, rng))
    assert exact <= approximate <= 1.05 * exact


def test_greedy_matches_the_closest_pair_first_and_beats_random():
    a, t, rng = scene(50, 40)
    chosen = assignment.greedy(a, t, rng)
    distance = cdist(t, a)
    target, agent = np.unravel_index(np.argmin(distance), distance.shape)
    assert chosen[target] == agent
    random_total = np.linalg.norm(a[assignment.random_assignment(a, t, rng)] - t, axis=1).sum()
    assert np.linalg.norm(a[chosen] - t, axis=1).sum() < random_total


@pytest.mark.parametrize("strategy", ["optimal", "greedy", "random", "paper"])
def test_runs_never_beat_their_lower_bounds(strategy):
    swarm = make_swarm(grid_from("####\n#..#\n####"), seed=4, strategy=strategy)
    run(swarm, max_steps=20_000)
    metrics = run_metrics(swarm)
    assert metrics["makespan_ratio"] >= 1.0
    assert metrics["distance_ratio"] >= 1.0
    assert metrics["groups"][0]["makespan_lower_bound"] == metrics["makespan_lower_bound"]

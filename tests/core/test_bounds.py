"""Lower bounds against brute force: exact where they say so, never above the truth."""

from __future__ import annotations

from collections import deque
from itertools import product

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import maximum_bipartite_matching, maximum_flow

from swarmshape.core import bounds
from swarmshape.core.bounds import (
    Bound,
    bottleneck_bound,
    distance_bound,
    travel_steps,
    unit_speed_optimum,
)
from swarmshape.core.motion import TOUCH, Limits, advance

# --- brute force ---------------------------------------------------------------------------


def pair_costs(starts: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """targets x robots L1 distances."""
    return np.abs(targets[:, None, :] - starts[None, :, :]).sum(axis=2)


def true_bottleneck(starts: np.ndarray, targets: np.ndarray) -> int:
    """Smallest threshold whose dense pair graph matches every target."""
    cost = pair_costs(starts, targets)
    for level in np.unique(cost):
        match = maximum_bipartite_matching(csr_matrix(cost <= level), perm_type="column")
        if (match >= 0).all():
            return int(level)
    raise AssertionError("unreachable")


def true_distance(starts: np.ndarray, targets: np.ndarray) -> int:
    cost = pair_costs(starts, targets)
    rows, cols = linear_sum_assignment(cost)
    return int(cost[rows, cols].sum())


@st.composite
def instances(draw, side: int = 12, most: int = 9):
    """Distinct robot cells and distinct target cells in a small box; the sets may overlap."""
    cell = st.tuples(st.integers(0, side - 1), st.integers(0, side - 1))
    n = draw(st.integers(1, most))
    m = draw(st.integers(1, n))
    starts = draw(st.lists(cell, min_size=n, max_size=n, unique=True))
    targets = draw(st.lists(cell, min_size=m, max_size=m, unique=True))
    return np.array(starts, dtype=np.int64), np.array(targets, dtype=np.int64)


# --- bottleneck ----------------------------------------------------------------------------


@settings(max_examples=100, deadline=None)
@given(instances())
def test_bottleneck_is_exact_when_it_says_so_and_a_bound_otherwise(case):
    starts, targets = case
    truth = true_bottleneck(starts, targets)
    found = bottleneck_bound(starts, targets)
    assert found.exact and found.method == "exact"
    assert found.value == truth
    hall = bottleneck_bound(starts, targets, budget_seconds=0.0)  # no time for a max flow
    assert not hall.exact and hall.method == "hall"
    assert hall.value <= truth
    for limit in ("GRID_LIMIT", "ROTATED_LIMIT"):  # points too spread out for grids
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(bounds, limit, 0)
            assert bounds._hall_bound(starts, targets) <= truth


@settings(max_examples=40, deadline=None)
@given(instances(side=20, most=30))
def test_threshold_network_matches_as_many_as_the_dense_graph(case):
    starts, targets = case
    cost = pair_costs(starts, targets)
    for d in np.unique(np.r_[0, cost.ravel()])[:12]:
        dense = maximum_bipartite_matching(csr_matrix(cost <= d), perm_type="column")
        graph, source, sink = bounds._threshold_network(starts, targets, int(d))
        assert maximum_flow(graph, source, sink).flow_value == (dense >= 0).sum()


def disc_instance(cells: int, robots: int, seed: int = 1):
    """A filled disc with robots at random free cells of a box around it, none touching it."""
    side = int(2 * np.sqrt(cells / np.pi)) + 3
    y, x = np.mgrid[:side, :side] - side / 2 + 0.5
    order = np.argsort(np.hypot(x, y).ravel(), kind="stable")
    shape = np.zeros(side * side, dtype=bool)
    shape[order[:cells]] = True
    arena = np.zeros((3 * side, 2 * side), dtype=bool)
    arena[side : 2 * side, side // 2 : side // 2 + side] = shape.reshape(side, side)
    near = ndimage.binary_dilation(arena, structure=np.ones((3, 3)))
    free = np.argwhere(~near)
    rng = np.random.default_rng(seed)
    return free[rng.choice(len(free), robots, replace=False)], np.argwhere(arena)


def subdisc_hall(starts: np.ndarray, targets: np.ndarray) -> int:
    """Hall's condition over nested sub-discs around the centre, checked level by level."""
    centre = targets.mean(axis=0)
    radius = np.hypot(*(targets - centre).T)
    low = np.minimum(starts.min(axis=0), targets.min(axis=0)) - 1
    size = np.maximum(starts.max(axis=0), targets.max(axis=0)) - low + 2
    best = 0
    for r in np.unique(np.ceil(radius)):
        inner = targets[radius <= r] - low
        grid = np.ones(size, dtype=bool)
        grid[inner[:, 0], inner[:, 1]] = False
        reach = ndimage.distance_transform_cdt(grid, metric="taxicab")[
            starts[:, 0] - low[0], starts[:, 1] - low[1]
        ]
        best = max(best, int(np.sort(reach)[len(inner) - 1]))
    return best


def test_hall_is_at_least_nested_subdiscs_and_beats_the_nearest_robot():
    starts, targets = disc_instance(400, 500)
    hall = bottleneck_bound(starts, targets, budget_seconds=0.0)
    nearest = pair_costs(starts, targets).min(axis=1).max()
    assert hall.method == "hall"
    assert hall.value >= subdisc_hall(starts, targets) > 1.5 * nearest
    assert hall.value <= bottleneck_bound(starts, targets).value == true_bottleneck(starts, targets)


def test_flows_search_up_from_the_lower_bound_and_stop_on_budget(monkeypatch):
    starts, targets = disc_instance(40, 60, seed=2)
    truth = true_bottleneck(starts, targets)
    monkeypatch.setattr(bounds, "_hall_bound", lambda s, t: 0)  # make the flows do the work
    assert bottleneck_bound(starts, targets) == Bound(float(truth), "exact", True)
    build, calls = bounds._threshold_network, []

    def counted(*args):
        calls.append(args)
        return build(*args)

    monkeypatch.setattr(bounds, "_threshold_network", counted)
    monkeypatch.setattr(bounds, "_flow_seconds", lambda s, t: 0.9)  # two flows fit in 2 s
    cut = bottleneck_bound(starts, targets, budget_seconds=2.0)
    assert len(calls) == 2
    assert cut.method == "hall+cut" and not cut.exact
    assert 0 < cut.value <= truth


def test_budgets_are_estimated_work_so_results_do_not_depend_on_load(monkeypatch):
    starts, targets = disc_instance(300, 400)
    first = (bottleneck_bound(starts, targets), distance_bound(starts, targets))
    clock = iter(range(0, 10**9, 1000))  # a clock on which every call takes 1,000 s
    monkeypatch.setattr("time.perf_counter", lambda: float(next(clock)))
    assert (bottleneck_bound(starts, targets), distance_bound(starts, targets)) == first


def test_bottleneck_inputs_are_checked():
    with pytest.raises(ValueError, match="need as many robots"):
        bottleneck_bound(np.zeros((1, 2)), np.array([[1, 1], [2, 2]]))
    assert bottleneck_bound(np.array([[3, 4]]), np.zeros((0, 2))) == Bound(0.0, "exact", True)


# --- total distance ------------------------------------------------------------------------


@settings(max_examples=100, deadline=None)
@given(instances())
def test_distance_is_exact_when_it_says_so_and_a_bound_otherwise(case):
    starts, targets = case
    truth = true_distance(starts, targets)
    found = distance_bound(starts, targets)
    assert found.exact and found.method == "exact"
    assert found.value == truth
    rushed = distance_bound(starts, targets, budget_seconds=0.0)
    assert rushed.method == "dual" and not rushed.exact
    assert rushed.value <= truth


@settings(max_examples=40, deadline=None)
@given(instances(side=30, most=40))
def test_separable_dual_never_exceeds_the_optimum(case):
    starts, targets = case
    truth = true_distance(starts, targets)
    phi_r, phi_t = bounds._start_potential(starts, targets, budget_seconds=np.inf)
    assert bounds._dual_value(phi_r, phi_t) <= truth
    assert distance_bound(starts, targets).value == truth


def test_large_instances_report_the_dual_bound(monkeypatch):
    starts, targets = disc_instance(300, 400)
    truth = true_distance(starts, targets)
    monkeypatch.setattr(bounds, "DENSE_PAIRS", 0)
    found = distance_bound(starts, targets)
    assert found.method == "dual" and not found.exact
    nearest = pair_costs(starts, targets).min(axis=1).sum()
    assert 0.999 * truth <= found.value <= truth
    assert found.value > 2 * nearest


def test_distance_inputs_are_checked():
    with pytest.raises(ValueError, match="whole lattice"):
        distance_bound(np.array([[0.5, 0.0]]), np.array([[1, 1]]))
    assert distance_bound(np.array([[3.0, 4.0]]), np.array([[3, 6]])) == Bound(2.0, "exact", True)


# --- travel steps --------------------------------------------------------------------------


def stepped(cells: int, limits: Limits, reserve_all: bool = True) -> int:
    """Steps the simulator takes for a straight run: `advance` plus `Swarm._move`'s
    bookkeeping; robots either hold the whole run or claim a cell whenever they hold at
    most one ahead, as `Swarm._reserve` does."""
    offset, speed = np.zeros(1), np.zeros(1)
    ahead = np.array([cells if reserve_all else 0])
    left, steps = cells - ahead[0], 0
    while cells and not (left == 0 and ahead[0] == 0):
        if ahead[0] <= 1 and left > 0:
            ahead += 1
            left -= 1
        advance(offset, speed, ahead, limits)
        steps += 1
        if offset[0] >= TOUCH:
            ahead -= 1
            offset -= 1.0
            if ahead[0] == 0:
                offset[:] = speed[:] = 0.0
    return steps


limits_strategy = st.tuples(st.floats(0.2, 1.0), st.floats(0.05, 1.0)).map(
    lambda va: Limits(va[0], min(va[1], va[0]))
)


@settings(max_examples=25, deadline=None)
@given(limits_strategy)
def test_travel_steps_count_what_advance_does(limits):
    cells = np.arange(25)
    expected = [stepped(int(d), limits) for d in cells]
    assert travel_steps(cells, limits).tolist() == expected
    assert travel_steps(7, limits) == expected[7]
    reserving = [stepped(int(d), limits, reserve_all=False) for d in cells[:12]]
    assert all(r >= e for r, e in zip(reserving, expected, strict=False))


def test_default_limits_take_two_steps_a_cell_and_three_to_start_and_stop():
    assert travel_steps(np.array([0, 1, 2, 55, 1000]), Limits()).tolist() == [0, 5, 7, 113, 2003]
    assert travel_steps(np.zeros((2, 3), int), Limits()).shape == (2, 3)


# --- the unit-speed optimum ----------------------------------------------------------------


def brute_makespan(passable: np.ndarray, starts: np.ndarray, targets: np.ndarray) -> int:
    """Breadth-first search over joint positions: robots wait or step to a free neighbour,
    never share a cell, never swap across an edge; done when every target holds one."""
    goal = {tuple(t) for t in targets.tolist()}
    moves = [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)]
    first = tuple(sorted(tuple(s) for s in starts.tolist()))
    seen, queue = {first}, deque([(first, 0)])
    while queue:
        state, depth = queue.popleft()
        if goal <= set(state):
            return depth
        for choice in product(moves, repeat=len(state)):
            after = [(x + dx, y + dy) for (x, y), (dx, dy) in zip(state, choice, strict=True)]
            if any(
                not (0 <= x < passable.shape[0] and 0 <= y < passable.shape[1])
                or not passable[x, y]
                for x, y in after
            ):
                continue
            if len(set(after)) < len(after):
                continue
            swap = any(
                after[i] == state[j] and after[j] == state[i]
                for i in range(len(state))
                for j in range(i + 1, len(state))
            )
            if swap:
                continue
            key = tuple(sorted(after))
            if key not in seen:
                seen.add(key)
                queue.append((key, depth + 1))
    raise AssertionError("no plan")


@st.composite
def tiny_worlds(draw):
    width, height = draw(st.integers(1, 4)), draw(st.integers(2, 4))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    passable = rng.random((width, height)) > 0.2
    cells = np.argwhere(passable)
    n = draw(st.integers(1, 3))
    if len(cells) < n + 1:
        passable[:] = True
        cells = np.argwhere(passable)
    n = min(n, len(cells) - 1)
    m = draw(st.integers(1, n))
    starts = cells[rng.choice(len(cells), n, replace=False)]
    targets = cells[rng.choice(len(cells), m, replace=False)]
    return passable, starts, targets


@settings(max_examples=60, deadline=None)
@given(tiny_worlds())
def test_unit_speed_optimum_matches_joint_state_search(world):
    passable, starts, targets = world
    labels, _ = ndimage.label(passable)
    have = np.bincount(labels[tuple(starts.T)], minlength=labels.max() + 1)
    need = np.bincount(labels[tuple(targets.T)], minlength=labels.max() + 1)
    if (need > have).any():
        with pytest.raises(ValueError, match="too few robots"):
            unit_speed_optimum(passable, starts, targets)
        return
    found = unit_speed_optimum(passable, starts, targets)
    assert found == brute_makespan(passable, starts, targets)
    assert found >= bottleneck_bound(starts, targets).value
    assert unit_speed_optimum(passable, starts, targets, upper=found + 3) == found


def test_walls_make_detours_and_doorways_make_robots_wait():
    passable = np.ones((5, 5), dtype=bool)
    passable[2, :4] = False  # a wall with a gap at y = 4
    detour = unit_speed_optimum(passable, np.array([[0, 0]]), np.array([[4, 0]]))
    assert detour == 12 > bottleneck_bound(np.array([[0, 0]]), np.array([[4, 0]])).value
    passable = np.ones((5, 3), dtype=bool)
    passable[3, [0, 2]] = False  # a one-cell doorway at (3, 1)
    starts, targets = np.array([[2, 0], [2, 1], [2, 2]]), np.array([[4, 0], [4, 1], [4, 2]])
    queued = unit_speed_optimum(passable, starts, targets)  # through the door one at a time
    assert queued == brute_makespan(passable, starts, targets) == 4
    assert bottleneck_bound(starts, targets).value == 2


def test_unit_speed_on_a_disc_equals_its_bottleneck():
    starts, targets = disc_instance(60, 80, seed=3)
    passable = np.ones(np.maximum(starts.max(axis=0), targets.max(axis=0)) + 1, dtype=bool)
    found = unit_speed_optimum(passable, starts, targets)
    assert found >= bottleneck_bound(starts, targets).value
    assert found <= bottleneck_bound(starts, targets).value + 2


def test_unit_speed_inputs_are_checked():
    with pytest.raises(ValueError, match="passable"):
        unit_speed_optimum(np.ones((2, 2), bool), np.array([[5, 5]]), np.array([[0, 0]]))
    with pytest.raises(ValueError, match="distinct"):
        unit_speed_optimum(np.ones((2, 2), bool), np.array([[0, 0], [0, 0]]), np.array([[1, 1]]))

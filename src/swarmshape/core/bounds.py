"""Lower bounds no run can beat, each honest about how it was obtained.

Robots start on distinct cells; each of ``m`` target cells needs its own robot (``n >= m``).
Distances are lattice (L1) distances in cells. Every function here is pure, takes start and
target cells as ``(k, 2)`` integer arrays, and depends on numpy and scipy only.

- `bottleneck_bound`: the smallest possible longest trip over all assignments.
- `distance_bound`: the least total distance of any assignment.
- `travel_steps`: steps a trip of so many cells takes under the simulator's speed limits.
- `unit_speed_optimum`: the exact fewest steps for unlabeled robots moving one cell a step.

A `Bound` says whether its value is the exact optimum or only a valid lower bound, and which
method produced it, so reports never present a bound as an optimum.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
import scipy

if TYPE_CHECKING:
    from swarmshape.core.motion import Limits

GRID_LIMIT = 40_000_000
"""Largest bounding box (cells) the grid methods allocate; the simulator's arenas are smaller."""

ROTATED_LIMIT = 100_000_000
"""Largest grid (cells) for a Hall family's max filter, about 1.2 GB at its peak; a family
that needs more is skipped, which can only weaken the bound."""

DENSE_PAIRS = 10_000_000
"""`distance_bound` proves optimality by dense dual ascent up to this many robot-target pairs
(3,000 x 3,000 takes under a second here); above it, it reports the separable dual bound."""

FLOW_SECONDS = 5e-9
"""scipy's max flow on the threshold network takes about this times arcs ** 1.4 seconds here
(0.5 s for 5e5 arcs at 10,000 robots, 13.5 s for 5.4e6 at 100,000), and the network has
about 7 arcs per hub; `bottleneck_bound` skips flows that would overrun its time budget.

Budgets are counted in these estimated seconds, never on the clock, so a bound and the method
it reports depend on the instance only, not on how busy the machine is."""

PAIR_SECONDS = 1e-7
"""One dense matching step of `distance_bound`'s ascent takes at most about this per
robot-target pair here (40 to 100 ns measured from 500 to 3,000 robots)."""

CELL_SECONDS = 2e-8
"""One distance transform of `_start_potential` takes about this per cell of its box."""

TOUCH = 1.0 - 1e-9
"""As in the simulator: a robot this close to a cell centre has arrived there."""

_NONE = np.iinfo(np.int32).min
"""Grid filler meaning "no value here" for the max filters."""


@dataclass(frozen=True)
class Bound:
    """A value in lattice cells; ``exact`` says it is the optimum, not just a lower bound.

    ``method`` names what produced the value: "exact" (proved optimal: a feasible matching at
    the lower bound, or dual potentials no step can improve), "hall" (Hall's condition over
    nested families), "hall+cut" (Hall raised by max flows that proved smaller thresholds
    infeasible), "dual" (Kantorovich duality with separable potentials), "dual+ascent"
    (those improved by dual ascent, stopped on budget).
    """

    value: float
    method: str
    exact: bool


# --- the bottleneck ------------------------------------------------------------------------


def bottleneck_bound(
    starts: np.ndarray, targets: np.ndarray, *, budget_seconds: float = 2.0
) -> Bound:
    """The smallest possible longest trip, exact when the time budget allows.

    First a lower bound from Hall's theorem (Hall 1935): every target set ``T`` needs at
    least ``|T|`` robots within distance ``d`` of it, and every robot set ``R`` at least
    ``|R| - (n - m)`` targets within ``d``. Checking nested families of sets (by depth in the
    shape, by distance from the robots, diamonds around the hardest target, robots by distance
    from the shape and from its centre) costs one max filter per family and threshold.

    Then the threshold test of the classical bottleneck assignment algorithm (Gross 1959,
    Garfinkel 1971): a max flow decides whether all targets can be matched within ``d``,
    on a network of linear size instead of the dense pair graph (see `_threshold_network`).
    A feasible ``d`` equal to the lower bound proves it exact; an infeasible one raises the
    bound. When the next flow would not fit in ``budget_seconds`` (estimated from the network's
    size, see `FLOW_SECONDS`), the bound found so far is returned, never the nearest-robot
    bound alone.
    """
    starts, targets = _cells(starts), _cells(targets)
    _check_counts(starts, targets)
    if len(targets) == 0:
        return Bound(0.0, "exact", True)
    lower = _hall_bound(starts, targets)
    method = "hall"
    feasible_at: int | None = None
    probe, gap = lower, 1
    cost, spent = _flow_seconds(starts, targets), 0.0
    while feasible_at is None or lower < feasible_at:
        spent += cost
        if spent > budget_seconds:
            return Bound(float(lower), method, False)
        graph, source, sink = _threshold_network(starts, targets, probe)
        flow = scipy.sparse.csgraph.maximum_flow(graph, source, sink, method="dinic")
        if flow.flow_value == len(targets):
            feasible_at = probe
        else:
            lower, method = probe + 1, "hall+cut"
        if feasible_at is None:
            probe, gap = lower + gap, 2 * gap  # gallop up from the proved bound
        else:
            probe = (lower + feasible_at) // 2
    return Bound(float(feasible_at), "exact", True)


def _hall_bound(starts: np.ndarray, targets: np.ndarray) -> int:
    """The largest threshold that Hall's condition rules out over a few nested families.

    Singletons first: some target's nearest robot (what the old code reported), and the
    ``(n - m + 1)``-th robot farthest from the shape, since one of those must be used. Then
    nested diamonds around two centres, by sorting (`_diamond_bound`). Then, exactly, target
    sets ``T_k = {t : g(t) >= k}``: the robots within ``d`` of ``T_k`` are those whose best
    ``g`` within distance ``d`` is at least ``k``, so one max filter checks every ``k`` at
    once (and likewise for robot sets). L1 balls are squares after rotating by 45 degrees
    (``u = x + y``, ``v = x - y``), where scipy's separable square max filter does it.
    """
    n, m = len(starts), len(targets)
    slack = n - m
    frame = _Frame.around(starts, targets)
    grids = frame.cells <= GRID_LIMIT  # else the points are too spread out for grids
    if grids:
        remoteness = frame.at(frame.distance_to(starts), targets)
        outlying = frame.at(frame.distance_to(targets), starts)
    else:
        remoteness, outlying = _nearest(starts, targets), _nearest(targets, starts)
    hardest = targets[np.argmax(remoteness)]
    centre = np.round(np.median(targets, axis=0)).astype(np.int64)
    lower = max(
        int(remoteness.max()),
        int(np.sort(outlying)[m - 1]),
        _diamond_bound(starts, targets, hardest, slack),
        _diamond_bound(starts, targets, centre, slack),
    )
    if not grids:
        return lower
    depth = frame.at(
        scipy.ndimage.distance_transform_cdt(frame.mask(targets), metric="taxicab"), targets
    )
    u_r, u_t = _rotated(starts), _rotated(targets)
    families: list[tuple[np.ndarray, np.ndarray, np.ndarray, int]] = [
        (u_t, depth, u_r, 0),
        (u_t, remoteness, u_r, 0),
        (u_t, -_l1(targets - hardest), u_r, 0),
        (u_r, outlying, u_t, slack),
        (u_r, _l1(starts - centre), u_t, slack),
    ]
    for family in families:
        lower = _first_true(partial(_hall_holds, *family), lower, frame.diameter)
    return lower


def _diamond_bound(starts: np.ndarray, targets: np.ndarray, centre: np.ndarray, slack: int) -> int:
    """Hall's condition for nested diamonds around `centre`, relaxed so a sort does it.

    A robot within ``d`` of a target inside the diamond of radius ``k`` lies inside the one
    of radius ``k + d``: so the ``T(k)``-th nearest robot to the centre bounds ``k + d`` from
    below. Likewise the robots outside radius ``k``, less the spare ones, need as many
    targets outside radius ``k - d``.
    """
    robots, shape = np.sort(_l1(starts - centre)), np.sort(_l1(targets - centre))
    inner = np.searchsorted(shape, shape, side="right")  # targets within each target's radius
    bound = int((robots[inner - 1] - shape).max())
    outside = len(robots) - np.arange(len(robots)) - slack  # robots at or beyond each radius
    short = outside > 0
    if short.any():
        bound = max(bound, int((robots[short] - shape[::-1][outside[short] - 1]).max()))
    return max(bound, 0)


def _hall_holds(src: np.ndarray, values: np.ndarray, dst: np.ndarray, spare: int, d: int) -> bool:
    """Whether every superlevel set of `values` over `src` has at least its size minus
    `spare` points of `dst` within distance `d` (all in rotated coordinates). Assumed to hold,
    which can only weaken the bound, when the grid would be too big."""
    levels, counts = np.unique(values, return_counts=True)
    need = np.cumsum(counts[::-1])[::-1] - spare
    best = _best_within(src, values, dst, d)
    if best is None:
        return True
    reach = np.sort(best)
    have = len(reach) - np.searchsorted(reach, levels, side="left")
    return bool((have >= need).all())


def _best_within(src: np.ndarray, values: np.ndarray, dst: np.ndarray, d: int) -> np.ndarray | None:
    """For each `dst` point, the largest value of a `src` point within L1 distance `d`.

    Points are in rotated coordinates, where the L1 ball is the square of side ``2d + 1``.
    The grid spans only where answers are needed plus the reach ``d`` around it; ``None``
    if that is more than `ROTATED_LIMIT` cells.
    """
    out = np.full(len(dst), _NONE, dtype=np.int64)
    lo = np.maximum(dst.min(axis=0), src.min(axis=0) - d)
    hi = np.minimum(dst.max(axis=0), src.max(axis=0) + d)
    if (hi < lo).any():
        return out
    grid_lo = np.maximum(lo - d, np.minimum(src.min(axis=0), lo))
    grid_hi = np.minimum(hi + d, np.maximum(src.max(axis=0), hi))
    if np.prod(grid_hi - grid_lo + 1) > ROTATED_LIMIT:
        return None
    grid = np.full(grid_hi - grid_lo + 1, _NONE, dtype=np.int32)
    keep = ((src >= grid_lo) & (src <= grid_hi)).all(axis=1)
    at = src[keep] - grid_lo
    np.maximum.at(grid, (at[:, 0], at[:, 1]), values[keep].astype(np.int32))
    best = scipy.ndimage.maximum_filter(grid, size=2 * d + 1, mode="constant", cval=_NONE)
    wanted = ((dst >= lo) & (dst <= hi)).all(axis=1)
    at = dst[wanted] - grid_lo
    out[wanted] = best[at[:, 0], at[:, 1]]
    return out


def _flow_seconds(starts: np.ndarray, targets: np.ndarray) -> float:
    """Estimated seconds of one max flow on `_threshold_network` (the same for every ``d``)."""
    u_r, v_r = np.unique(starts.sum(axis=1)), np.unique(starts[:, 0] - starts[:, 1])
    u_t, v_t = np.unique(targets.sum(axis=1)), np.unique(targets[:, 0] - targets[:, 1])
    hubs = min(len(u_t) * len(v_r), len(v_t) * len(u_r))
    return FLOW_SECONDS * (7 * hubs) ** 1.4  # measured 5.6 to 6.8 arcs per hub before pruning


def _threshold_network(
    starts: np.ndarray, targets: np.ndarray, d: int
) -> tuple[scipy.sparse.csr_matrix, int, int]:
    """A flow network whose max flow is the largest matching of pairs within distance `d`.

    The pair graph is dense (each target sees thousands of robots), so it is never built. In
    rotated coordinates ``|dx| + |dy| <= d`` iff ``|du| <= d`` and ``|dv| <= d``: a robot
    goes along its ``v`` line to a hub ``(u', v)`` whose ``u'`` is some target's ``u``, then
    along that ``u'`` column to the target. Each leg reaches a window of receivers on a line,
    which a sparse table or a segment tree over the receivers covers (`_fan_out`). Robots and
    targets carry capacity 1, everything else is unbounded.
    """
    u_r, v_r = starts.sum(axis=1), starts[:, 0] - starts[:, 1]
    u_t, v_t = targets.sum(axis=1), targets[:, 0] - targets[:, 1]
    if len(np.unique(v_t)) * len(np.unique(u_r)) < len(np.unique(u_t)) * len(np.unique(v_r)):
        u_r, v_r, u_t, v_t = v_r, u_r, v_t, u_t  # the mirror image y -> -y swaps u and v
    hub_u, hub_v = np.unique(u_t), np.unique(v_r)
    # leg 1 runs along lines v (robots' v values), leg 2 along columns u' (targets' u values)
    u0, v0 = min(u_r.min(), u_t.min()), min(v_r.min(), v_t.min())
    stride_u = int(max(u_r.max(), u_t.max()) - u0) + 2 * d + 2  # windows never cross lines
    stride_v = int(max(v_r.max(), v_t.max()) - v0) + 2 * d + 2
    line = np.repeat(np.arange(len(hub_v)), len(hub_u))
    column = np.tile(np.arange(len(hub_u)), len(hub_v))
    hub_key1 = line * stride_u + (hub_u[column] - u0)
    hub_key2 = column * stride_v + (hub_v[line] - v0)
    robot_key = np.searchsorted(hub_v, v_r) * stride_u + (u_r - u0)
    target_key = np.searchsorted(hub_u, u_t) * stride_v + (v_t - v0)
    useful = (_gap_to(np.sort(robot_key), hub_key1) <= d) & (
        _gap_to(np.sort(target_key), hub_key2) <= d
    )
    hub_key1, hub_key2 = hub_key1[useful], hub_key2[useful]
    order = np.argsort(target_key, kind="stable")
    inner1, send1, size1 = _fan_out(hub_key1, robot_key, d)
    inner2, send2, size2 = _fan_out(target_key[order], hub_key2, d)
    n, m = len(starts), len(targets)
    source, sink, robots = 0, 1, 2
    table1 = robots + n  # its first nodes are the hubs
    table2 = table1 + size1  # its first nodes are the targets, in key order
    tails = [np.zeros(n, np.int64), table2 + np.arange(m)]
    heads = [robots + np.arange(n), np.ones(m, np.int64)]
    legs = ((table1, inner1, robots, send1), (table2, inner2, table1, send2))
    for first, inner, sender, send in legs:
        tails += [first + inner[0], sender + send[0]]
        heads += [first + inner[1], first + send[1]]
    tail, head = np.concatenate(tails), np.concatenate(heads)
    capacity = np.full(len(tail), m, dtype=np.int32)
    capacity[: n + m] = 1
    nodes = table2 + size2
    return scipy.sparse.csr_matrix((capacity, (tail, head)), shape=(nodes, nodes)), source, sink


def _fan_out(
    receivers: np.ndarray, senders: np.ndarray, d: int
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray], int]:
    """Arcs from each sender to every receiver whose key is within `d` of its own, through
    helper nodes: the table's internal arcs, the senders' arcs ``(sender index, node)``, and
    the node count. `receivers` are sorted keys and the first ``k`` nodes.

    A sparse table (Bender and Farach-Colton 2000) covers a window with two blocks, so each
    sender needs two arcs but the table has ``k log k`` arcs; a segment tree has ``2k`` arcs
    and each sender ``2 log k``. Whichever has fewer arcs is used: scipy's max flow time grows
    like arcs ** 1.5 here.
    """
    k = len(receivers)
    first = np.searchsorted(receivers, senders - d, side="left")
    last = np.searchsorted(receivers, senders + d, side="right") - 1
    reaching = np.flatnonzero(last >= first)
    if k == 0 or len(reaching) == 0:
        empty = np.zeros(0, np.int64)
        return (empty, empty), (empty, empty), k
    first, last = first[reaching], last[reaching]
    levels = int(np.log2(k)) + 1
    if 2 * k + 2 * len(reaching) * levels < 2 * k * levels + 2 * len(reaching):
        inner, (which, node), size = _segment_tree(k, first, last)
    else:
        inner, (which, node), size = _sparse_table(k, first, last)
    return inner, (reaching[which], node), size


def _sparse_table(
    k: int, first: np.ndarray, last: np.ndarray
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray], int]:
    """Node ``(j, i)`` stands for receivers ``i .. i + 2**j - 1``, with arcs to its halves;
    a range is the union of the two blocks of its length's power of two at its ends."""
    level = np.floor(np.log2(last - first + 1)).astype(np.int64)
    top = int(level.max())
    start = np.zeros(top + 2, np.int64)  # node id of (j, 0)
    for j in range(1, top + 2):
        start[j] = start[j - 1] + k - (1 << (j - 1)) + 1
    tails, heads = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for j in range(1, top + 1):
        i = np.arange(k - (1 << j) + 1)
        tails += [start[j] + i, start[j] + i]
        heads += [start[j - 1] + i, start[j - 1] + i + (1 << (j - 1))]
    which = np.arange(len(first))
    ends = np.concatenate([start[level] + first, start[level] + last - (1 << level) + 1])
    return (np.concatenate(tails), np.concatenate(heads)), (np.tile(which, 2), ends), int(start[-1])


def _segment_tree(
    k: int, first: np.ndarray, last: np.ndarray
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray], int]:
    """The bottom-up segment tree: node ``j < k`` has children ``2j`` and ``2j + 1``, leaves
    ``k .. 2k - 1`` are the receivers, and a range is covered by the usual walk up from its
    ends (all senders at once, one level per pass). Renumbered so receivers come first."""

    def local(node: np.ndarray) -> np.ndarray:
        return np.where(node >= k, node - k, node + k - 1)

    parent = np.arange(1, k)
    inner = (local(np.repeat(parent, 2)), local(np.stack([2 * parent, 2 * parent + 1], 1).ravel()))
    low, high = first + k, last + 1 + k
    which, nodes = [], []
    sender = np.arange(len(first))
    while True:
        active = low < high
        if not active.any():
            break
        left = active & (low % 2 == 1)
        which.append(sender[left])
        nodes.append(low[left])
        low = low + left
        right = active & (high % 2 == 1)
        high = high - right
        which.append(sender[right])
        nodes.append(high[right])
        low, high = low // 2, high // 2
    return inner, (np.concatenate(which), local(np.concatenate(nodes))), 2 * k - 1


def _gap_to(sorted_keys: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Distance from each key to the nearest of `sorted_keys` (a huge number if none)."""
    gap = np.full(len(keys), np.iinfo(np.int64).max)
    if len(sorted_keys) == 0:
        return gap
    at = np.searchsorted(sorted_keys, keys)
    right = at < len(sorted_keys)
    gap[right] = sorted_keys[at[right]] - keys[right]
    left = at > 0
    gap[left] = np.minimum(gap[left], keys[left] - sorted_keys[at[left] - 1])
    return gap


# --- the total distance ----------------------------------------------------------------------


def distance_bound(
    starts: np.ndarray, targets: np.ndarray, *, budget_seconds: float = 2.0
) -> Bound:
    """The least total distance of any assignment, exact where dense dual ascent fits.

    Kantorovich duality (Kantorovich and Rubinstein 1958): for any potential ``phi`` that
    changes by at most 1 per unit of L1 distance, every assignment costs at least
    ``D(phi) = sum_t phi(t) - sum_r max(phi(r), 0)``, since a robot going from ``r`` to ``t``
    travels at least ``phi(t) - phi(r)`` and unused robots add nothing. (Target potentials
    ``u`` with ``v_r = min(0, min_t |r - t| - u_t)`` give the same family.) Strong duality
    makes the best ``D`` equal to the optimum.

    The start is mostly separable, ``phi(x, y) = f(x) + g(y)`` with ``f`` and ``g`` the
    potentials of the optimal 1-D transports of the x and y marginals: O(n log n), and within
    0.01 % of the optimum on large filled discs (`_start_potential`). Up to `DENSE_PAIRS`
    pairs, steepest ascent then closes the gap and proves optimality (`_steepest_ascent`);
    above, or when `budget_seconds` run out (estimated from the instance's size, see
    `PAIR_SECONDS` and `CELL_SECONDS`), the value is a bound and says so.
    """
    starts, targets = _cells(starts), _cells(targets)
    _check_counts(starts, targets)
    if len(targets) == 0:
        return Bound(0.0, "exact", True)
    phi_r, phi_t = _start_potential(starts, targets, budget_seconds / 2)
    start = _dual_value(phi_r, phi_t)
    pairs = len(starts) * len(targets)
    if pairs > DENSE_PAIRS:
        return Bound(float(start), "dual", False)
    matchings = budget_seconds / (PAIR_SECONDS * pairs)
    phi_r, phi_t, optimal = _steepest_ascent(starts, targets, phi_r, phi_t, matchings)
    value = _dual_value(phi_r, phi_t)
    if optimal:
        return Bound(float(value), "exact", True)
    return Bound(float(value), "dual+ascent" if value > start else "dual", False)


def _start_potential(
    starts: np.ndarray, targets: np.ndarray, budget_seconds: float
) -> tuple[np.ndarray, np.ndarray]:
    """The best of a few cheap potentials, each 1-Lipschitz in L1 and so each a valid dual.

    With ``n = m`` the marginal potentials are the best separable ones, and measured within
    0.06 % of the optimum on discs, rings and stars. With spare robots it is not known which
    robots are used: the marginals are also tried with the ``m`` robots nearest the shape,
    the diamond ``-|p - c|`` around the shape's median cell, and, while time remains,
    ``-dist(p, core)`` for the cores of targets at depth >= 1, 2, 4, ... (depth 1: every
    target, which bounds the total by the ``m`` robots nearest the shape). These help thin
    and hollow shapes, where the marginals alone can be 25 % low or worse.
    """
    n, m = len(starts), len(targets)
    candidates = [_separable(starts, targets, np.full(n, m / n))]
    if n > m:
        near = np.argsort(_to_shape(starts, targets), kind="stable")[:m]
        weights = np.zeros(n)
        weights[near] = 1.0
        candidates.append(_separable(starts, targets, weights))
        centre = np.round(np.median(targets, axis=0)).astype(np.int64)
        candidates.append((-_l1(starts - centre), -_l1(targets - centre)))
        frame = _Frame.around(starts, targets)
        if frame.cells <= GRID_LIMIT:
            depth = scipy.ndimage.distance_transform_cdt(frame.mask(targets), metric="taxicab")
            depth = frame.at(depth, targets)
            core, transforms = 1, budget_seconds / (CELL_SECONDS * frame.cells)
            while core <= depth.max() and transforms >= 1:
                transforms -= 1
                inward = frame.distance_to(targets[depth >= core])
                candidates.append((-frame.at(inward, starts), -frame.at(inward, targets)))
                core *= 2
    return max(candidates, key=lambda pair: _dual_value(*pair))


def _separable(
    starts: np.ndarray, targets: np.ndarray, weights: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``f(x) + g(y)``: along each axis the potential rises by one per cell across every gap
    that (weighted) robots must cross left to right and falls where they cross right to left.
    """
    n = len(starts)
    phi = np.zeros(n + len(targets), np.int64)
    for axis in (0, 1):
        where = np.concatenate([starts[:, axis], targets[:, axis]])
        places, slot = np.unique(where, return_inverse=True)
        supply = np.bincount(slot[:n], weights=weights, minlength=len(places))
        demand = np.bincount(slot[n:], minlength=len(places))
        crossing = np.cumsum(supply - demand)[:-1]  # robots crossing each gap rightward
        slope = np.where(np.abs(crossing) < 1e-9, 0, np.sign(crossing)).astype(np.int64)
        phi += np.concatenate([[0], np.cumsum(slope * np.diff(places))])[slot]
    return phi[:n], phi[n:]


def _dual_value(phi_r: np.ndarray, phi_t: np.ndarray) -> int:
    """``D`` at the best constant shift of the potentials: the shift that leaves exactly the
    ``m`` robots with the highest potential at or above zero."""
    n, m = len(phi_r), len(phi_t)
    shift = -np.partition(phi_r, n - m)[n - m]
    return int((phi_t + shift).sum() - np.maximum(phi_r + shift, 0).sum())


def _steepest_ascent(
    starts: np.ndarray,
    targets: np.ndarray,
    phi_r: np.ndarray,
    phi_t: np.ndarray,
    matchings: float,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Raise or lower the potentials by one on an improving set until none is left.

    ``D`` is L-natural-concave in integer potentials (Murota, "Discrete Convex Analysis",
    2003): it is maximal iff no unit raise or lowering of a set improves it, and ascent by such
    steps takes about as many steps as the distance to an optimum (Murota and Shioura 2014).
    A set may move only with everything tightly "downhill" of it (``phi(p) - phi(q) =
    |p - q|``), or Lipschitz breaks; potentials live on robots and targets only, which is
    enough (a 1-Lipschitz function on points extends to the plane, McShane 1934). The best
    raise gains the deficiency of the tight graph between targets and robots with ``phi >= 0``,
    the best lowering that between robots with ``phi >= 1`` and targets: maximum matchings
    (Hopcroft and Karp 1973), whose unmatched vertices' alternating paths reach the set (Konig
    1931), as in the Hungarian method (Kuhn 1955). At most `matchings` matchings are solved.
    Returns the potentials and whether they are proved optimal: neither direction improves.
    """
    n, m = len(starts), len(targets)
    shift = -np.partition(phi_r, n - m)[n - m]
    phi_r, phi_t = phi_r + shift, phi_t + shift
    distance = np.abs(starts[:, None, 0] - targets[None, :, 0]) + np.abs(
        starts[:, None, 1] - targets[None, :, 1]
    )
    directions = ["raise", "lower"]
    while True:
        tight = (phi_t[None, :] - phi_r[:, None]) == distance  # robots x targets
        for direction in directions:
            if matchings < 1:
                return phi_r, phi_t, False
            matchings -= 1
            if direction == "raise":  # targets up, with robots downhill of them
                chosen, gain = _deficient_set(tight[phi_r >= 0], from_targets=True)
                if gain:
                    phi_t = phi_t + chosen
                    phi_r = phi_r + tight[:, chosen].any(axis=1)
            else:  # robots down, with targets uphill of them
                earning = np.flatnonzero(phi_r >= 1)
                chosen, gain = _deficient_set(tight[earning], from_targets=False)
                if gain:
                    robots = np.zeros(n, bool)
                    robots[earning[chosen]] = True
                    phi_r = phi_r - robots
                    phi_t = phi_t - tight[robots].any(axis=0)
            if gain:
                directions.reverse()  # the other direction is likelier to gain next
                break
        else:
            return phi_r, phi_t, True


def _deficient_set(adjacency: np.ndarray, *, from_targets: bool) -> tuple[np.ndarray, int]:
    """A most deficient set of one side of a bipartite graph (robots x targets, dense), and
    its deficiency: its size minus its neighbours', which is that side's count minus the
    maximum matching (Konig). It is what alternating paths from the unmatched vertices of
    that side reach. Robots are the rows because scipy's Hopcroft-Karp runs about five times
    faster that way on these graphs, and both sides go in order of rising degree, which makes
    its greedy start nearly maximum (10 to 30 times faster again)."""
    rows = np.argsort(adjacency.sum(axis=1), kind="stable")
    cols = np.argsort(adjacency.sum(axis=0), kind="stable")
    graph = scipy.sparse.csr_matrix(adjacency[rows][:, cols])
    robots, targets = adjacency.shape
    # robot -> target, sorted
    match = scipy.sparse.csgraph.maximum_bipartite_matching(graph, perm_type="column")
    matched = np.flatnonzero(match >= 0)
    owner = np.full(targets, -1)
    owner[match[matched]] = matched
    edge_robot = np.repeat(np.arange(robots), np.diff(graph.indptr))
    edge_target = robots + graph.indices
    root = robots + targets
    if from_targets:  # free target -> any robot -> the target it is matched to
        free = robots + np.flatnonzero(owner < 0)
        tails = [edge_target, matched, np.full(len(free), root)]
        heads = [edge_robot, robots + match[matched], free]
    else:  # free robot -> any target -> the robot matched to it
        free = np.flatnonzero(match < 0)
        owned = np.flatnonzero(owner >= 0)
        tails = [edge_robot, robots + owned, np.full(len(free), root)]
        heads = [edge_target, owner[owned], free]
    side, order = (slice(robots, root), cols) if from_targets else (slice(0, robots), rows)
    chosen = np.zeros(len(order), bool)
    if len(free) == 0:
        return chosen, 0
    tail, head = np.concatenate(tails), np.concatenate(heads)
    arcs = scipy.sparse.csr_matrix(
        (np.ones(len(tail), np.int8), (tail, head)), shape=(root + 1, root + 1)
    )
    reached = np.zeros(root + 1, bool)
    seen = scipy.sparse.csgraph.breadth_first_order(arcs, root, return_predecessors=False)
    reached[seen] = True
    chosen[order] = reached[side]
    return chosen, len(free)


# --- time under the speed limits -------------------------------------------------------------


def travel_steps(cells: np.ndarray | int, limits: Limits) -> np.ndarray | int:
    """Steps to travel `cells` straight from rest to rest, as the simulator counts them.

    `swarmshape.motion.advance` raises the speed by at most ``a`` a step, caps it at ``v`` and
    at what still lets it brake at ``a`` onto the last reserved centre, and a robot within
    ``1 - TOUCH`` of a centre has arrived. With the whole run reserved, that is the fastest
    discrete profile: in ``k`` steps it covers at most ``sum_i min(v, a * min(i, k + 1 - i))``
    (accelerate, cruise, mirror-image braking), so the count is the least ``k`` whose reach
    covers the distance. Reserving cells a few at a time, as robots do, can only be slower,
    and any route of L1 length ``d`` is at least a straight ``d``: turns stop the robot.
    Vectorised (a bisection on ``k``); scalars in, int out.
    """
    distance = np.asarray(cells, dtype=np.float64)
    v, a = float(limits.max_speed), float(limits.max_accel)
    need = distance - (1.0 - TOUCH)
    low = np.zeros(distance.shape, np.int64)
    high = np.ceil(distance / v + 2 * v / a).astype(np.int64) + 4
    while (low < high).any():
        middle = (low + high) // 2
        enough = _reach(middle, v, a) >= need
        high = np.where(enough, middle, high)
        low = np.where(enough, low, middle + 1)
    return int(low) if low.ndim == 0 else low


def _reach(steps: np.ndarray, v: float, a: float) -> np.ndarray:
    """Farthest distance from rest to rest in `steps` steps (see `travel_steps`)."""
    ramp = int(np.floor(v / a))  # steps of pure acceleration; an off-by-one here is harmless

    def half(h: np.ndarray) -> np.ndarray:
        accelerating = np.minimum(h, ramp)
        return a * accelerating * (accelerating + 1) / 2 + v * (h - accelerating)

    return 2 * half(steps // 2) + (steps % 2) * np.minimum(v, a * ((steps + 1) // 2))


# --- the unit-speed optimum ------------------------------------------------------------------


def unit_speed_optimum(
    passable: np.ndarray,
    starts: np.ndarray,
    targets: np.ndarray,
    *,
    upper: int | None = None,
) -> int:
    """Fewest steps until every target holds a robot, moving one cell a step, exactly.

    `passable` is a boolean ``(width, height)`` grid indexed ``[x, y]`` (seed cells False;
    outside it is wall). Robots are unlabeled and may wait; no two share a cell at any step.
    As Yu and LaValle ("Multi-agent path planning and network flow", WAFR 2012) show, plans
    of ``T`` steps are integral flows in a time-expanded network: cell ``c`` at time ``tau``
    is a node of capacity 1 with arcs to itself and its neighbours at ``tau + 1``. All ``n``
    robots are routed (spare ones are obstacles too, free to step aside); at time ``T`` each
    target takes one and the other cells at most ``n - m``.

    Head-on swaps are not excluded by gadgets: two unlabeled robots swapping across an edge
    leave the same occupied cells as two that wait, so a flow with swaps can be rewritten
    without them and the optimum is unchanged (likewise for cycles). ``T`` is searched
    upward from the bottleneck bound, which is usually the answer or close; `upper`, a
    makespan known to be achievable, caps the search.
    """
    passable = np.asarray(passable, dtype=bool)
    starts, targets = _cells(starts), _cells(targets)
    _check_counts(starts, targets)
    for name, cells in (("start", starts), ("target", targets)):
        inside = ((cells >= 0) & (cells < passable.shape)).all(axis=1)
        if not inside.all() or not passable[cells[:, 0], cells[:, 1]].all():
            raise ValueError(f"every {name} cell must be a passable cell of the grid")
        if len(np.unique(cells, axis=0)) < len(cells):
            raise ValueError(f"{name} cells must be distinct")
    if len(targets) == 0:
        return 0
    plan = _TimeExpansion(passable, starts, targets)
    lower = max(plan.lower_bound(), int(bottleneck_bound(starts, targets).value))
    if upper is not None:
        if upper < lower:
            raise ValueError(f"upper {upper} is below the proved lower bound {lower}")
        return _first_true(plan.feasible, lower, upper)
    return _first_true(plan.feasible, lower)


class _TimeExpansion:
    """The passable grid as a graph, and the time-expanded flow test for a makespan ``T``."""

    def __init__(self, passable: np.ndarray, starts: np.ndarray, targets: np.ndarray) -> None:
        width, height = passable.shape
        cells = np.flatnonzero(passable.ravel())
        index = np.full(passable.size, -1)
        index[cells] = np.arange(len(cells))
        x, y = np.divmod(cells, height)
        tails, heads = [np.arange(len(cells))], [np.arange(len(cells))]  # waiting
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            ok = (x + dx >= 0) & (x + dx < width) & (y + dy >= 0) & (y + dy < height)
            there = np.full(len(cells), -1)
            there[ok] = index[(x[ok] + dx) * height + y[ok] + dy]
            tails.append(np.flatnonzero(there >= 0))
            heads.append(there[there >= 0])
        self.tail, self.head = np.concatenate(tails), np.concatenate(heads)
        self.size = len(cells)
        self.starts = index[starts[:, 0] * height + starts[:, 1]]
        self.targets = index[targets[:, 0] * height + targets[:, 1]]
        self.from_starts = self._hops(self.starts)
        self.to_targets = self._hops(self.targets)
        labels, _ = scipy.ndimage.label(passable)
        robots = np.bincount(labels[starts[:, 0], starts[:, 1]], minlength=labels.max() + 1)
        wanted = np.bincount(labels[targets[:, 0], targets[:, 1]], minlength=labels.max() + 1)
        if (wanted > robots).any():
            raise ValueError("some targets lie in a region with too few robots to fill them")

    def _hops(self, sources: np.ndarray) -> np.ndarray:
        """Steps from the nearest of `sources` to every cell (breadth-first search)."""
        root = self.size
        tail = np.concatenate([self.tail, np.full(len(sources), root)])
        head = np.concatenate([self.head, sources])
        graph = scipy.sparse.csr_matrix(
            (np.ones(len(tail)), (tail, head)), shape=(root + 1, root + 1)
        )
        hops = scipy.sparse.csgraph.shortest_path(graph, indices=root, unweighted=True)
        hops = hops[: self.size] - 1
        return np.where(np.isfinite(hops), hops, np.iinfo(np.int32).max).astype(np.int64)

    def lower_bound(self) -> int:
        """Each target's nearest robot, and with no spare robots each robot's nearest target,
        around obstacles."""
        bound = self.from_starts[self.targets].max()
        if len(self.starts) == len(self.targets):
            bound = max(bound, self.to_targets[self.starts].max())
        return int(bound)

    def feasible(self, steps: int) -> bool:
        """Whether some plan of `steps` steps fills every target (one max flow)."""
        n, m = len(self.starts), len(self.targets)
        time_ = np.arange(steps + 1)[:, None]
        alive = self.from_starts[None, :] <= time_  # reachable by then
        if n == m:  # every robot must still reach a target
            alive &= self.to_targets[None, :] <= steps - time_
        if not alive[0, self.starts].all():
            return False
        count = int(alive.sum())
        ids = np.int32 if 2 * count + 4 < 2**31 else np.int64  # halves the biggest arrays
        node = np.full(alive.shape, -1, ids)
        node[alive] = np.arange(count, dtype=ids)
        source, at_target, elsewhere, sink = 2 * count + np.arange(4)
        last = node[steps]
        on_target = np.zeros(self.size, bool)
        on_target[self.targets] = True
        ends = np.flatnonzero(last >= 0)
        # inside each node: capacity 1
        tails: list[npt.ArrayLike] = [2 * node[alive], np.full(n, source)]
        heads: list[npt.ArrayLike] = [2 * node[alive] + 1, 2 * node[0, self.starts]]
        move_from, move_to = node[:-1, self.tail], node[1:, self.head]
        moves = (move_from >= 0) & (move_to >= 0)
        tails += [2 * move_from[moves] + 1, 2 * last[ends] + 1, [at_target, elsewhere]]
        heads += [
            2 * move_to[moves],
            np.where(on_target[ends], at_target, elsewhere),
            [sink, sink],
        ]
        tail, head = np.concatenate(tails), np.concatenate(heads)
        capacity = np.ones(len(tail), np.int32)
        capacity[-2:] = m, n - m
        graph = scipy.sparse.csr_matrix(
            (capacity, (tail, head)), shape=(2 * count + 4, 2 * count + 4)
        )
        flow = scipy.sparse.csgraph.maximum_flow(graph, source, sink, method="dinic")
        return flow.flow_value == n


# --- shared helpers --------------------------------------------------------------------------


def _first_true(predicate: Callable[[int], bool], low: int, high: int | None = None) -> int:
    """Least ``x >= low`` with ``predicate(x)``, for a monotone predicate known to hold at
    `high` (never evaluated there) or somewhere when `high` is None: gallop, then bisect."""
    step = 1
    while high is None or low < high:
        probe = low + step - 1
        if high is not None and probe >= high:
            break
        if predicate(probe):
            high = probe
            break
        low, step = probe + 1, 2 * step
    while low < high:
        middle = (low + high) // 2
        if predicate(middle):
            high = middle
        else:
            low = middle + 1
    return low


@dataclass(frozen=True)
class _Frame:
    """A bounding box of cells with a one-cell margin, for distance transforms."""

    origin: np.ndarray
    shape: tuple[int, int]

    @classmethod
    def around(cls, *sets: np.ndarray) -> _Frame:
        cells = np.concatenate(sets)
        low, high = cells.min(axis=0) - 1, cells.max(axis=0) + 1
        return cls(low, (int(high[0] - low[0]) + 1, int(high[1] - low[1]) + 1))

    @property
    def cells(self) -> int:
        return self.shape[0] * self.shape[1]

    @property
    def diameter(self) -> int:
        """No two cells of the box are farther apart (in L1) than this."""
        return self.shape[0] + self.shape[1]

    def mask(self, cells: np.ndarray) -> np.ndarray:
        grid = np.zeros(self.shape, dtype=bool)
        grid[cells[:, 0] - self.origin[0], cells[:, 1] - self.origin[1]] = True
        return grid

    def at(self, grid: np.ndarray, cells: np.ndarray) -> np.ndarray:
        return grid[cells[:, 0] - self.origin[0], cells[:, 1] - self.origin[1]].astype(np.int64)

    def distance_to(self, cells: np.ndarray) -> np.ndarray:
        """L1 distance from every cell of the box to the nearest of `cells`: the taxicab
        chamfer transform is exact on an open grid."""
        return scipy.ndimage.distance_transform_cdt(~self.mask(cells), metric="taxicab")


def _to_shape(starts: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Each robot's L1 distance to the nearest target."""
    frame = _Frame.around(starts, targets)
    if frame.cells > GRID_LIMIT:
        return _nearest(targets, starts)
    return frame.at(frame.distance_to(targets), starts)


def _nearest(points: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """L1 distance from each query to the nearest point, without a grid."""
    from scipy.spatial import cKDTree

    return cKDTree(points).query(queries, p=1)[0].astype(np.int64)


def _rotated(cells: np.ndarray) -> np.ndarray:
    """``(x + y, x - y)``: L1 balls become axis-aligned squares."""
    return np.stack([cells[:, 0] + cells[:, 1], cells[:, 0] - cells[:, 1]], axis=1)


def _l1(offsets: np.ndarray) -> np.ndarray:
    return np.abs(offsets).sum(axis=1)


def _cells(cells: np.ndarray) -> np.ndarray:
    """Cells as an ``(k, 2)`` int64 array; float input must hold whole numbers."""
    array = np.asarray(cells)
    if array.size == 0:
        return np.zeros((0, 2), np.int64)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"cells must be a (k, 2) array, got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.integer) and not np.array_equal(array, np.round(array)):
        raise ValueError("cells must be whole lattice coordinates")
    return array.astype(np.int64)


def _check_counts(starts: np.ndarray, targets: np.ndarray) -> None:
    if len(starts) < len(targets):
        raise ValueError(f"{len(targets)} targets need as many robots; got {len(starts)}")

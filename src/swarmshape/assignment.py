"""Who goes to which target: assignment problems between agent cells and target cells.

Every function takes agent positions ``(n, 2)`` and target positions ``(m, 2)`` with
``n >= m`` and returns, for each target, the index of the agent that goes there.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import maximum_bipartite_matching
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

EXACT_LIMIT = 1500 * 1500
"""Largest agents x targets for exact Hungarian assignment (1,000 x 1,000 takes ~0.25 s)."""

LEAF = 128
"""Above the limit, space is bisected until a part has this many targets, then solved exactly:
within 1 % of the exact total on the shapes we measured (see scripts/bench.py)."""


def random_assignment(
    agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """A uniformly random choice of agents, the worst-case baseline."""
    return rng.permutation(len(agents))[: len(targets)]


def greedy(agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Nearest free target: in rounds, every free target asks its nearest free agent, and each
    agent takes the nearest target that asked. The closest free pair always matches, so every
    round makes progress; ties fall to the lower index, so `rng` is not needed."""
    chosen = np.full(len(targets), -1)
    free_agents = np.arange(len(agents))
    free_targets = np.arange(len(targets))
    while len(free_targets):
        _, nearest = cKDTree(agents[free_agents]).query(targets[free_targets])
        asked = free_agents[nearest]
        distance = np.linalg.norm(agents[asked] - targets[free_targets], axis=1)
        order = np.lexsort((free_targets, distance))
        _, first = np.unique(asked[order], return_index=True)
        winners = order[first]
        chosen[free_targets[winners]] = asked[winners]
        free_targets = np.delete(free_targets, winners)
        free_agents = np.setdiff1d(free_agents, asked[winners], assume_unique=True)
    return chosen


def optimal(agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Least total squared distance (CAPT: such paths do not cross in free space).

    Exact with the Hungarian method up to `EXACT_LIMIT`; above it, the agents nearest to the
    shape are taken, one per target, and recursive bisection splits the targets at the median
    of the longer axis, gives each half the agents that come first along that axis, and solves
    parts of `LEAF` targets exactly.
    """
    chosen = np.empty(len(targets), dtype=np.int64)
    if len(agents) * len(targets) <= EXACT_LIMIT:
        chosen[:] = _hungarian(agents, targets)
        return chosen
    nearest, _ = cKDTree(targets).query(agents)
    taken = np.argsort(nearest, kind="stable")[: len(targets)]
    _bisect(agents, targets, taken, np.arange(len(targets)), chosen)
    return chosen


def _hungarian(agents: np.ndarray, targets: np.ndarray) -> np.ndarray:
    _, agent = linear_sum_assignment(cdist(targets, agents, "sqeuclidean"))
    return agent


def _bisect(
    agents: np.ndarray, targets: np.ndarray, a: np.ndarray, t: np.ndarray, out: np.ndarray
) -> None:
    if len(t) <= LEAF:
        out[t] = a[_hungarian(agents[a], targets[t])]
        return
    spread = np.ptp(np.concatenate([agents[a], targets[t]]), axis=0)
    axis = int(np.argmax(spread))
    t = t[np.argsort(targets[t, axis], kind="stable")]
    a = a[np.argsort(agents[a, axis], kind="stable")]
    half = len(t) // 2
    _bisect(agents, targets, a[:half], t[:half], out)
    _bisect(agents, targets, a[half:], t[half:], out)


def manhattan_lower_bounds(agents: np.ndarray, targets: np.ndarray) -> tuple[float, float, bool]:
    """``(longest, total, exact)``: lattice distances no assignment can beat.

    ``longest`` is the bottleneck optimum (the smallest possible longest trip) and ``total``
    the least total distance. Above `EXACT_LIMIT` both fall back to the nearest-agent distance
    of each target (its max and its sum), which are still lower bounds, and ``exact`` is False.
    """
    if len(agents) * len(targets) > EXACT_LIMIT:
        nearest, _ = cKDTree(agents).query(targets, p=1)
        return float(nearest.max()), float(nearest.sum()), False
    cost = cdist(targets, agents, "cityblock")
    rows, cols = linear_sum_assignment(cost)
    return _bottleneck(cost), float(cost[rows, cols].sum()), True


def _bottleneck(cost: np.ndarray) -> float:
    """Smallest threshold under which every target can still get its own agent."""
    levels = np.unique(cost)
    low, high = int(np.searchsorted(levels, cost.min(axis=1).max())), len(levels) - 1
    while low < high:
        middle = (low + high) // 2
        graph = csr_matrix(cost <= levels[middle])
        if (maximum_bipartite_matching(graph, perm_type="column") >= 0).all():
            high = middle
        else:
            low = middle + 1
    return float(levels[low])

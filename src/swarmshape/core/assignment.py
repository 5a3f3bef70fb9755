"""Who goes to which target: assignment problems between agent cells and target cells.

Every function takes agent positions ``(n, 2)`` and target positions ``(m, 2)`` with
``n >= m`` and returns, for each target, the index of the agent that goes there.

scipy's submodules are imported where they are used: `scipy.optimize` alone takes half a
second to import, and only the exact assignment needs it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

EXACT_LIMIT = 1500 * 1500
"""Largest agents x targets for exact Hungarian assignment. On cells of a grid, whose squared
distances tie often, scipy 1.17's solver takes 0.12 s at 500 x 500, 1.3 to 1.5 s at 1,000 x
1,000 and 4 to 5 s at 1,500 x 1,500 on the 2-core machine of `scripts/bench.py`."""

GREEDY_CANDIDATES = 8
"""Nearest targets each agent considers per round in `greedy`."""

GREEDY_LIMIT = 20_000
GREEDY_LEAF = 1024
"""`greedy` runs whole up to this many targets (~0.8 s), in parts of GREEDY_LEAF above."""

Solver = Callable[[np.ndarray, np.ndarray], np.ndarray]
Matcher = Callable[[np.ndarray, np.ndarray, np.random.Generator], np.ndarray]
"""(agents, targets, rng) -> for each target, the index of its agent."""

LEAF = 128
"""Above the limit, space is bisected until a part has this many targets, then solved exactly:
within 1 % of the exact total on the shapes we measured (0.2 % on a 1,000-cell disc)."""


def random_assignment(
    agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """A uniformly random choice of agents, the worst-case baseline."""
    return rng.permutation(len(agents))[: len(targets)]


def greedy(agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Nearest free target: agents, closest to the shape first, each take their nearest free
    target. Above `GREEDY_LIMIT` targets, space is split as in `optimal` and each part is
    solved greedily (rounds grow with the shape's depth, so one huge greedy pass is slow)."""
    if len(targets) <= GREEDY_LIMIT:
        return _greedy_rounds(agents, targets)
    return _by_parts(agents, targets, GREEDY_LEAF, _greedy_rounds)


def _greedy_rounds(agents: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """An agent whose few nearest targets went to others tries again in the next round,
    against the targets still free. Ties fall to the lower index."""
    from scipy.spatial import cKDTree

    chosen = np.full(len(targets), -1)
    reach, _ = cKDTree(targets).query(agents)
    queue = np.argsort(reach, kind="stable")
    free = np.arange(len(targets))
    while len(free):
        count = min(GREEDY_CANDIDATES, len(free))
        _, options = cKDTree(targets[free]).query(agents[queue], k=count)
        taken = np.zeros(len(free), dtype=bool)
        later = []
        for agent, nearest in zip(
            queue.tolist(), options.reshape(len(queue), -1).tolist(), strict=True
        ):
            choice = next((option for option in nearest if not taken[option]), None)
            if choice is None:
                later.append(agent)
                continue
            taken[choice] = True
            chosen[free[choice]] = agent
        free, queue = free[~taken], np.array(later, dtype=np.int64)
    return chosen


def optimal(agents: np.ndarray, targets: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Least total squared distance (CAPT: such paths do not cross in free space).

    Exact with the Hungarian method up to `EXACT_LIMIT`; above it, the agents nearest to the
    shape are taken, one per target, space is bisected recursively, and parts of `LEAF`
    targets are solved exactly.
    """
    if len(agents) * len(targets) <= EXACT_LIMIT:
        return _hungarian(agents, targets)
    return _by_parts(agents, targets, LEAF, _hungarian)


def _hungarian(agents: np.ndarray, targets: np.ndarray) -> np.ndarray:
    from scipy.optimize import linear_sum_assignment
    from scipy.spatial.distance import cdist

    _, agent = linear_sum_assignment(cdist(targets, agents, "sqeuclidean"))
    return agent


def _by_parts(agents: np.ndarray, targets: np.ndarray, leaf: int, solve: Solver) -> np.ndarray:
    """Take the agents nearest the shape, one per target, then solve spatial parts apart."""
    from scipy.spatial import cKDTree

    chosen = np.empty(len(targets), dtype=np.int64)
    nearest, _ = cKDTree(targets).query(agents)
    taken = np.argsort(nearest, kind="stable")[: len(targets)]
    _bisect(agents, targets, taken, np.arange(len(targets)), chosen, leaf, solve)
    return chosen


def _bisect(
    agents: np.ndarray,
    targets: np.ndarray,
    a: np.ndarray,
    t: np.ndarray,
    out: np.ndarray,
    leaf: int,
    solve: Solver,
) -> None:
    """Split the targets at the median of the longer axis and give each half the agents
    that come first along that axis, until parts have `leaf` targets."""
    if len(t) <= leaf:
        out[t] = a[solve(agents[a], targets[t])]
        return
    spread = np.ptp(np.concatenate([agents[a], targets[t]]), axis=0)
    axis = int(np.argmax(spread))
    t = t[np.argsort(targets[t, axis], kind="stable")]
    a = a[np.argsort(agents[a, axis], kind="stable")]
    half = len(t) // 2
    _bisect(agents, targets, a[:half], t[:half], out, leaf, solve)
    _bisect(agents, targets, a[half:], t[half:], out, leaf, solve)

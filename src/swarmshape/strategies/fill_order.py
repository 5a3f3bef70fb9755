"""The paper's target function: the order in which a group's target cells get filled.

An order is first a preference (``outward`` from the seeds, ``left-to-right`` as the paper's
line, or ``random``), then made safe: a cell is only filled once filling it cannot wall any
unfilled cell off from the open arena, so a robot can always reach the next target.
"""

from __future__ import annotations

import heapq

import numpy as np
import scipy

from swarmshape.core.motion import STEPS
from swarmshape.core.world import World, WorldError
from swarmshape.errors import InputError

ORDERS = ("outward", "left-to-right", "random")
DEFAULT_ORDER = ORDERS[0]


def fill_sequence(world: World, group: int, order: str, rng: np.random.Generator) -> np.ndarray:
    """Indices into ``world.groups[group].targets``: the preferred order, made safe."""
    return safe_sequence(world, group, preference(world, group, order, rng))


def preference(world: World, group: int, order: str, rng: np.random.Generator) -> np.ndarray:
    """A rank per target cell (lower fills earlier), before safety is considered."""
    placed = world.groups[group]
    if order == "random":
        return rng.permutation(len(placed.targets))
    if order == "left-to-right":  # in the seed frame, so a rotated shape keeps its order
        return _ranks(np.lexsort((placed.frame_cells[:, 1], placed.frame_cells[:, 0])))
    if order == "outward":
        return _ranks(np.argsort(_outward_distance(placed.targets, placed.seeds), kind="stable"))
    raise InputError(f"unknown order {order!r}; choose one of {', '.join(ORDERS)}")


def _ranks(sequence: np.ndarray) -> np.ndarray:
    ranks = np.empty_like(sequence)
    ranks[sequence] = np.arange(len(sequence))
    return ranks


def _outward_distance(cells: np.ndarray, seeds: np.ndarray) -> np.ndarray:
    """Breadth-first distance through the shape from the seeds.

    Each connected part of the shape starts at its cell nearest the seeds, offset by that
    cell's straight distance, so the wave grows along the shape and jumps gaps in seed order.
    """
    graph = _adjacency(cells)
    to_seeds = np.abs(cells[:, None, :] - seeds[None, :, :]).sum(axis=2).min(axis=1)
    _, part = scipy.sparse.csgraph.connected_components(graph, directed=False)
    starts = [np.flatnonzero(part == p)[np.argmin(to_seeds[part == p])] for p in np.unique(part)]
    # one extra node (index k) that reaches each part's start at that start's seed distance
    k = len(cells)
    extra = scipy.sparse.coo_matrix(
        (to_seeds[starts] + 1.0, (np.full(len(starts), k), starts)), shape=(k + 1, k + 1)
    )
    full = scipy.sparse.block_diag([graph, scipy.sparse.csr_matrix((1, 1))]) + extra
    return scipy.sparse.csgraph.dijkstra(full, directed=True, indices=k)[:k]


def _adjacency(cells: np.ndarray) -> scipy.sparse.csr_matrix:
    """Unit-weight graph joining 4-neighbour cells of the set, both directions."""
    index = {tuple(c): i for i, c in enumerate(cells.tolist())}
    pairs = [
        (i, index[(x + dx, y + dy)])
        for i, (x, y) in enumerate(cells.tolist())
        for dx, dy in ((1, 0), (0, 1))
        if (x + dx, y + dy) in index
    ]
    rows, cols = np.array(pairs, dtype=np.int64).reshape(-1, 2).T
    n = len(cells)
    upper = scipy.sparse.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return (upper + upper.T).tocsr()


def safe_sequence(world: World, group: int, rank: np.ndarray) -> np.ndarray:
    """Follow `rank` as closely as possible while never sealing an unfilled cell in.

    Built backwards by peeling: repeatedly remove, among the cells that touch the open arena,
    the one preferred last. Filling in the reverse of that removal order means every cell, when
    its turn comes, still touches open space through cells filled after it.
    """
    cells = world.groups[group].targets
    own = world.mask(cells)
    others = world.mask(world.seeds) | (world.mask(world.targets) & ~own)
    index = np.full(world.size, -1)
    index[cells[:, 0], cells[:, 1]] = np.arange(len(cells))
    regions, _ = scipy.ndimage.label(~own & ~others)
    width, height = world.size
    border = np.concatenate([regions[0], regions[-1], regions[:, 0], regions[:, -1]])
    opened = set(border[border > 0].tolist())
    touching = _cells_touching_regions(regions, index)

    heap = [(-rank[i], i) for label in opened for i in touching.get(label, ())]
    heapq.heapify(heap)
    peeled = np.zeros(len(cells), dtype=bool)
    removal = []
    while heap:
        _, i = heapq.heappop(heap)
        if peeled[i]:
            continue
        peeled[i] = True
        removal.append(i)
        for x, y in cells[i] + STEPS[1:]:
            if not (0 <= x < width and 0 <= y < height):
                continue
            if index[x, y] >= 0 and not peeled[index[x, y]]:
                heapq.heappush(heap, (-rank[index[x, y]], index[x, y]))
            elif regions[x, y] and regions[x, y] not in opened:  # a hole opens up
                opened.add(regions[x, y])
                for j in touching.get(regions[x, y], ()):
                    heapq.heappush(heap, (-rank[j], j))
    if not peeled.all():
        name = world.groups[group].name
        raise WorldError(f"group {name!r}: some cells are sealed off by other groups; move them")
    return np.array(removal[::-1], dtype=np.int64)


def _cells_touching_regions(regions: np.ndarray, index: np.ndarray) -> dict[int, list[int]]:
    """For each open region label, the target cells (by index) next to it."""
    touching: dict[int, set[int]] = {}
    for axis in (0, 1):
        for a, b in ((slice(None, -1), slice(1, None)), (slice(1, None), slice(None, -1))):
            region = regions[(a, slice(None)) if axis == 0 else (slice(None), a)]
            target = index[(b, slice(None)) if axis == 0 else (slice(None), b)]
            hit = (region > 0) & (target >= 0)
            for label, i in zip(region[hit].tolist(), target[hit].tolist(), strict=True):
                touching.setdefault(label, set()).add(i)
    return {label: sorted(ids) for label, ids in touching.items()}

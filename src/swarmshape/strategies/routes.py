"""Shortest ways round a shape, as a robot that knows the shape's bitmap can work them out.

A local program plans over the few cells its robot senses, and a formed shape is an obstacle
far wider than that: a robot on the wrong side of an arm, whose target faces the shape's bay,
walked back and forth along the arm for a thousand steps. Every robot knows the bitmap and
the seeds in its frame, so it can find the way round them alone: the path through cells
outside the shape that ends on its target. Robots in the way are left to the local planner.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Blueprint
from swarmshape.core.shape import SEED_CELLS

MARGIN = 4
"""Cells of outside kept round the shape's box: room to walk round its rim. A robot farther
out walks straight in until it is within the margin."""


def waypoints(
    blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray, target: np.ndarray, ahead: int
) -> tuple[np.ndarray, np.ndarray]:
    """For robots outside their shape, the cell `ahead` steps along the shortest way round the
    shape to each one's `target` (a shape cell with outside beside it), and whether there is
    such a way."""
    found = np.zeros(len(frame), dtype=bool)
    out = target.copy()
    for group in np.unique(groups):
        rows = np.flatnonzero(groups == group)
        low, size = _box(blueprint, int(group))
        ends, which = np.unique(target[rows], axis=0, return_inverse=True)
        fields = np.stack([_field(blueprint, int(group), x, y) for x, y in ends.tolist()])
        which = which.reshape(-1)
        at = frame[rows] - low
        for _ in range(ahead):
            here = _distance(fields, which, at, size)
            best, step = here, np.zeros(len(rows), dtype=np.int64)
            for direction in range(1, len(STEPS)):
                there = _distance(fields, which, at + STEPS[direction], size)
                better = there < best
                best, step = np.where(better, there, best), np.where(better, direction, step)
            at = at + STEPS[step]
        reached = np.isfinite(_distance(fields, which, at, size))
        found[rows] = reached
        out[rows[reached]] = at[reached] + low
    return out, found


def _distance(fields: np.ndarray, which: np.ndarray, at: np.ndarray, size: np.ndarray):
    """Each robot's distance to its target along its field, at cells `at` (inf off the box)."""
    inside = ((at >= 0) & (at < size)).all(axis=1)
    distance = np.full(len(at), np.inf)
    distance[inside] = fields[which[inside], at[inside, 0], at[inside, 1]]
    return distance


@functools.lru_cache(maxsize=16)
def _box(blueprint: Blueprint, group: int) -> tuple[np.ndarray, np.ndarray]:
    """The low corner and size of the group's shape box (seeds included), with the margin."""
    cells = np.concatenate([blueprint.cells[group], SEED_CELLS])
    low = cells.min(axis=0) - MARGIN
    return low, cells.max(axis=0) + MARGIN + 1 - low


@functools.lru_cache(maxsize=16)
def _moves(blueprint: Blueprint, group: int):
    """The moves a route may take, as a graph over the box's cells, reversed (from the
    target out): from a free cell to a free one, and out of a shape cell onto a free one, so
    the one shape cell a route enters is its end. Seeds are never crossed."""
    low, size = _box(blueprint, group)
    shape = np.zeros(size, dtype=bool)
    cells = blueprint.cells[group] - low
    shape[cells[:, 0], cells[:, 1]] = True
    seeds = np.zeros(size, dtype=bool)
    seeds[SEED_CELLS[:, 0] - low[0], SEED_CELLS[:, 1] - low[1]] = True
    free = ~shape & ~seeds
    index = np.arange(shape.size).reshape(size)
    sources, sinks = [], []
    for dx, dy in ((1, 0), (0, 1)):
        a = index[: size[0] - dx, : size[1] - dy]
        b = index[dx:, dy:]
        for one, other in ((a, b), (b, a)):
            ok = free.ravel()[other] & ~seeds.ravel()[one]
            sources.append(one[ok])
            sinks.append(other[ok])
    sources, sinks = np.concatenate(sources), np.concatenate(sinks)
    ones = np.ones(len(sources))
    return coo_matrix((ones, (sources, sinks)), shape=(shape.size, shape.size)).tocsr()


@functools.lru_cache(maxsize=4096)
def _field(blueprint: Blueprint, group: int, x: int, y: int) -> np.ndarray:
    """Steps from each cell of the box to frame cell ``(x, y)`` by a route round the shape
    (inf: none, or the target is off the box)."""
    low, size = _box(blueprint, group)
    local = np.array([x, y]) - low
    if not ((local >= 0) & (local < size)).all():
        return np.full(tuple(size), np.inf)
    graph = _moves(blueprint, group)
    start = int(local[0] * size[1] + local[1])
    return dijkstra(graph, indices=start, unweighted=True).reshape(tuple(size))

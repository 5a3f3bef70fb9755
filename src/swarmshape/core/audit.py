"""An independent check that no two squares overlap, from positions alone.

It never reads the lattice's reservations, so it checks them: a bug that lets two robots into
one cell shows up as a counted overlap, not as a silent picture glitch.
"""

from __future__ import annotations

import numpy as np

from swarmshape.core.motion import STEPS, TOUCH, positions

DENSE_LIMIT = 40
"""Squares up to which `overlapping_pairs` compares every pair instead of hashing."""


def overlaps(
    cell: np.ndarray,
    direction: np.ndarray,
    offset: np.ndarray,
    seeds: np.ndarray,
    size: tuple[int, int],
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)`` of overlapping squares among the robots and then the seeds
    (seed ``s`` is number ``len(cell) + s``).

    A square covers its cell, and the next one too while it is between the two; squares that
    overlap share a cell, so only squares sharing one need the exact test. Two squares may
    share a cell without overlapping (one leaving it as the other comes in behind it), but
    never three, so every pair in a shared cell is tested.
    """
    between = np.flatnonzero(offset > 0)
    covered = np.concatenate([cell, cell[between] + STEPS[direction[between]], seeds])
    owners = np.concatenate([np.arange(len(cell)), between, len(cell) + np.arange(len(seeds))])
    keys = (covered[:, 0] + 1) * (size[1] + 2) + covered[:, 1] + 1
    shared = np.bincount(keys, minlength=(size[0] + 2) * (size[1] + 2))[keys] > 1
    if not shared.any():
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    i, j = _pairs_in_cells(keys[shared], owners[shared])
    at_i, at_j = (_centres(k, cell, direction, offset, seeds) for k in (i, j))
    touching_or_apart = np.abs(at_i - at_j).max(axis=1) >= TOUCH
    return i[~touching_or_apart], j[~touching_or_apart]


def _centres(
    which: np.ndarray,
    cell: np.ndarray,
    direction: np.ndarray,
    offset: np.ndarray,
    seeds: np.ndarray,
) -> np.ndarray:
    """Square centres of robots and seeds by number (seed ``s`` is ``len(cell) + s``), for
    the few that share a cell rather than for all."""
    robot = np.minimum(which, len(cell) - 1)
    at = positions(cell[robot], direction[robot], offset[robot])
    is_seed = which >= len(cell)
    at[is_seed] = seeds[which[is_seed] - len(cell)] + 0.5
    return at


def _pairs_in_cells(keys: np.ndarray, owners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every pair of distinct owners that share a key (a cell)."""
    order = np.argsort(keys, kind="stable")
    keys, owners = keys[order], owners[order]
    found_i, found_j = [], []
    gap = 1
    while gap < len(keys):  # pairs a gap apart within each run of one key
        first = np.flatnonzero(keys[gap:] == keys[:-gap])
        if len(first) == 0:
            break
        found_i.append(owners[first])
        found_j.append(owners[first + gap])
        gap += 1
    i, j = np.concatenate(found_i), np.concatenate(found_j)
    distinct = i != j
    return i[distinct], j[distinct]


def overlapping_pairs(pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)``, ``i != j``, of unit squares that overlap, without O(n^2) work.

    A spatial hash: overlapping squares have centres in the same or an adjacent cell, so
    squares are bucketed by the cell of their centre (a sort plus dense per-cell counts and
    starts) and each one tests only the buckets in half of its 3x3 neighbourhood. Up to
    `DENSE_LIMIT` squares, comparing every pair at once is cheaper than building the hash.
    """
    n = len(pos)
    if n < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if n <= DENSE_LIMIT:
        close = np.abs(pos[:, None, :] - pos[None, :, :]).max(axis=2) < TOUCH
        i, j = np.nonzero(np.triu(close, k=1))
        return i, j
    cell = np.floor(pos).astype(np.int64)
    cell -= cell.min(axis=0) - 1  # a free ring of buckets around, so neighbours stay in range
    stride = int(cell[:, 1].max()) + 2
    key = cell[:, 0] * stride + cell[:, 1]
    count = np.bincount(key, minlength=(int(cell[:, 0].max()) + 2) * stride)
    start = np.cumsum(count) - count
    order = np.argsort(key, kind="stable")
    found_i, found_j = [], []
    for dx, dy in ((0, 0), (1, -1), (1, 0), (1, 1), (0, 1)):
        wanted = key + dx * stride + dy
        hits = count[wanted]
        i = np.repeat(np.arange(n), hits)
        rank = np.arange(len(i)) - np.repeat(np.cumsum(hits) - hits, hits)
        j = order[np.repeat(start[wanted], hits) + rank]
        keep = i < j if (dx, dy) == (0, 0) else np.ones(len(i), dtype=bool)
        keep &= np.abs(pos[i] - pos[j]).max(axis=1) < TOUCH
        found_i.append(i[keep])
        found_j.append(j[keep])
    return np.concatenate(found_i), np.concatenate(found_j)

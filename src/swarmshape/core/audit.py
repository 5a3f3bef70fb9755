"""An independent check that no two squares overlap, from positions alone.

It never reads the lattice's reservations, so it checks them: a bug that lets two robots into
one cell shows up as a counted overlap, not as a silent picture glitch.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from swarmshape.core.compiled import njit
from swarmshape.core.motion import STEPS, TOUCH

DENSE_LIMIT = 40
"""Squares up to which `overlapping_pairs` compares every pair instead of hashing."""


def overlaps(
    cell: np.ndarray,
    direction: np.ndarray,
    offset: np.ndarray,
    seeds: np.ndarray,
    size: tuple[int, int],
    present: np.ndarray | None = None,
    scratch: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)`` of overlapping squares among the robots (those `present`, all by
    default) and then the seeds (seed ``s`` is number ``len(cell) + s``).

    A square covers its cell, and the next one too while it is between the two; squares that
    overlap share a cell, so only squares sharing one need the exact test. Two squares may
    share a cell without overlapping (one leaving it as the other comes in behind it), but
    never three, so every pair in a shared cell is tested (a pair sharing two cells counts
    twice). `scratch` is a per-cell array of -1 the caller keeps (`new_scratch`), so a step
    costs the squares and not the arena; it is left as it was found.
    """
    if present is None:
        present = np.ones(len(cell), dtype=bool)
    if scratch is None:
        scratch = new_scratch(size)
    pairs = _shared_cell_pairs(cell, direction, offset, present, seeds, size[1] + 2, scratch)
    return pairs[:, 0], pairs[:, 1]


def new_scratch(size: tuple[int, int]) -> np.ndarray:
    """The per-cell array `overlaps` works in, for an arena of `size` (with its ring of walls)."""
    return np.full((size[0] + 2) * (size[1] + 2), -1, dtype=np.int64)


@njit
def _shared_cell_pairs(
    cell: np.ndarray, direction: np.ndarray, offset: np.ndarray, present: np.ndarray,
    seeds: np.ndarray, stride: int, first: np.ndarray,
) -> npt.NDArray[np.int64]:  # pragma: no cover (compiled)  # fmt: skip
    """Pairs ``(k, 2)`` of overlapping squares: every square goes into the list of each cell it
    covers (`first` holds a list's latest entry per cell, -1 for none) and is tested against
    the squares already there. Squares in order: robots, then seeds."""
    n, m = len(cell), len(seeds)
    dxs, dys = STEPS[:, 0], STEPS[:, 1]
    key = np.empty(2 * n + m, dtype=np.int64)
    owner = np.empty(2 * n + m, dtype=np.int64)
    after = np.empty(2 * n + m, dtype=np.int64)
    centre = np.empty((n + m, 2))
    found: list[tuple[int, int]] = []
    entries = 0
    for square in range(n + m):
        if square < n:
            if not present[square]:
                continue
            x, y, dx, dy = (
                cell[square, 0],
                cell[square, 1],
                dxs[direction[square]],
                dys[direction[square]],
            )
            centre[square, 0] = x + 0.5 + offset[square] * dx
            centre[square, 1] = y + 0.5 + offset[square] * dy
            covers = 2 if offset[square] > 0 else 1
        else:
            x, y, dx, dy, covers = seeds[square - n, 0], seeds[square - n, 1], 0, 0, 1
            centre[square, 0], centre[square, 1] = x + 0.5, y + 0.5
        home = (x + 1) * stride + y + 1
        for part in range(covers):
            here = home + part * (dx * stride + dy)
            other = first[here]
            while other >= 0:
                o = owner[other]
                if o != square:
                    apart = max(
                        abs(centre[o, 0] - centre[square, 0]), abs(centre[o, 1] - centre[square, 1])
                    )
                    if apart < TOUCH:
                        found.append((o, square))
                other = after[other]
            key[entries], owner[entries], after[entries] = here, square, first[here]
            first[here] = entries
            entries += 1
    for entry in range(entries):
        first[key[entry]] = -1
    pairs = np.empty((len(found), 2), dtype=np.int64)
    for k in range(len(found)):
        pairs[k, 0], pairs[k, 1] = found[k]
    return pairs


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

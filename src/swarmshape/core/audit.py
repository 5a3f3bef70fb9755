"""An independent check that no two squares overlap, from positions alone.

It never reads the lattice's reservations, so it checks them: a bug that lets two robots into
one cell shows up as a counted overlap, not as a silent picture glitch.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from swarmshape.core.compiled import njit
from swarmshape.core.motion import STEPS, TOUCH


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
    """Index pairs ``(i, j)``, ``i != j``, of unit squares that overlap, without O(n^2) work:
    overlapping squares have centres in the same or an adjacent cell, so each square is tested
    only against those already listed in the 3x3 cells round its centre's (`_close_pairs`).
    A square whose centre is not a finite number overlaps nothing (the caller reports it)."""
    finite = np.flatnonzero(np.isfinite(pos).all(axis=1))
    if len(finite) < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    pos = pos[finite]
    cell = np.floor(pos).astype(np.int64)
    cell -= cell.min(axis=0) - 1  # a free ring of cells around, so neighbours stay in range
    pairs = finite[_close_pairs(pos, cell, int(cell[:, 1].max()) + 2, int(cell[:, 0].max()) + 2)]
    return pairs[:, 0], pairs[:, 1]


@njit
def _close_pairs(
    pos: np.ndarray, cell: np.ndarray, stride: int, rows: int
) -> npt.NDArray[np.int64]:  # pragma: no cover (compiled)  # fmt: skip
    """Pairs ``(k, 2)`` of squares closer than `TOUCH` on both axes: each square goes into its
    cell's list (`first` holds a list's latest entry, `after` the entry before it) after it is
    tested against the lists of the nine cells round it."""
    first = np.full(rows * stride, -1, dtype=np.int64)
    after = np.empty(len(pos), dtype=np.int64)
    found: list[tuple[int, int]] = []
    for square in range(len(pos)):
        home = cell[square, 0] * stride + cell[square, 1]
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                other = first[home + dx * stride + dy]
                while other >= 0:
                    apart = max(
                        abs(pos[other, 0] - pos[square, 0]), abs(pos[other, 1] - pos[square, 1])
                    )
                    if apart < TOUCH:
                        found.append((other, square))
                    other = after[other]
        after[square], first[home] = first[home], square
    pairs = np.empty((len(found), 2), dtype=np.int64)
    for k in range(len(found)):
        pairs[k, 0], pairs[k, 1] = found[k]
    return pairs

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


class Audit:
    """`overlaps`, step after step, at the cost of the squares that moved. A square at rest
    covers only its own cell, so two at rest overlap only in one cell, and one of them came to
    rest there after the other: each robot at rest (and each seed) stays entered in a per-cell
    table from step to step, and a step tests only the squares under way against it and each
    other, and enters the robots that came to rest, checking the cell was free. Like
    `overlaps`, it reads positions alone, never the lattice. A step that finds an overlap, and
    every step after one until a step is clean (an overlap lasts until its squares part), is
    audited whole by `overlaps`, which names the pairs: the counts are the same as calling it
    every step. At 1,000,000 robots the whole audit was a fifth of a step (55 ms), most of it
    spent looking up a cell of a 35 MB table for every robot, at rest or not; kept from step to
    step it takes 4.0 ms where it took 40.7 ms (the disc's step 40, 5,800 robots under way). At
    100,000 robots, whose table fits the cache, the two cost about the same."""

    def __init__(self, size: tuple[int, int]) -> None:
        self.size = size
        self._rest = new_scratch(size)
        """Per cell (flat key, as `overlaps`), the robot or seed (robots, then seeds) at rest."""
        self._entered = np.zeros(0, dtype=np.int64)
        """Per robot, the key it is entered at in `_rest`, or -1."""
        self.stale = True
        """Audit the next step whole: at the start, and after an overlap."""

    def pairs(
        self,
        cell: np.ndarray,
        direction: np.ndarray,
        offset: np.ndarray,
        seeds: np.ndarray,
        present: np.ndarray,
        scratch: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """What `overlaps` returns for these squares (`scratch` as there)."""
        if not self.stale and len(self._entered) == len(cell):
            stride = self.size[1] + 2
            clean = _moved_clean(
                cell, direction, offset, present, stride, self._rest, self._entered, scratch
            )
            if clean:
                return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        i, j = overlaps(cell, direction, offset, seeds, self.size, present, scratch)
        self.stale = len(i) > 0
        if not self.stale:
            self._enter_all(cell, offset, seeds, present)
        return i, j

    def _enter_all(
        self, cell: np.ndarray, offset: np.ndarray, seeds: np.ndarray, present: np.ndarray
    ) -> None:
        """Fill the table afresh from squares that do not overlap."""
        stride = self.size[1] + 2
        self._rest.fill(-1)
        resting = present & (offset <= 0)
        self._entered = np.where(resting, (cell[:, 0] + 1) * stride + cell[:, 1] + 1, -1)
        self._rest[self._entered[resting]] = np.flatnonzero(resting)
        self._rest[(seeds[:, 0] + 1) * stride + seeds[:, 1] + 1] = len(cell) + np.arange(len(seeds))


@njit
def _moved_clean(
    cell: np.ndarray, direction: np.ndarray, offset: np.ndarray, present: np.ndarray,
    stride: int, rest: np.ndarray, entered: np.ndarray, first: np.ndarray,
) -> bool:  # pragma: no cover (compiled)  # fmt: skip
    """`Audit`'s step: bring the table up to date (each robot that left its cell or the
    lattice taken out, each that came to rest entered), and test the squares under way against
    it and against each other (the one under way in each cell noted in `first`, left -1).
    False if any overlaps: the table is then no longer to be trusted."""
    n = len(cell)
    for r in range(n):
        key = -1
        if present[r] and offset[r] <= 0:
            key = (cell[r, 0] + 1) * stride + cell[r, 1] + 1
        if entered[r] != key:
            if entered[r] >= 0 and rest[entered[r]] == r:
                rest[entered[r]] = -1
            entered[r] = key
            if key >= 0:
                other = rest[key]  # a robot later in order may have left the cell this step
                there = other >= 0 and _rests_on(cell, offset, present, other, key, stride)
                if other >= n or there:
                    return False  # a seed or a robot at rest there already
                rest[key] = r
    clean = True
    for r in range(n):  # each square under way, against those in the two cells it covers
        if not present[r] or offset[r] <= 0:
            continue
        dx, dy = STEPS[direction[r], 0], STEPS[direction[r], 1]
        for part in range(2):
            x, y = cell[r, 0] + part * dx, cell[r, 1] + part * dy
            here = (x + 1) * stride + y + 1
            apart = max(abs(part * dx - offset[r] * dx), abs(part * dy - offset[r] * dy))
            clean &= rest[here] < 0 or apart >= TOUCH
            other = first[here]  # a square under way there: -1 none, -2 two already
            if other >= 0:
                clean &= _apart(cell, direction, offset, r, other) >= TOUCH
            clean &= other != -2  # never three without an overlap (see `overlaps`)
            first[here] = r if other == -1 else -2
    for r in range(n):
        if present[r] and offset[r] > 0:
            for part in range(2):
                x, y = (
                    cell[r, 0] + part * STEPS[direction[r], 0],
                    cell[r, 1] + part * STEPS[direction[r], 1],
                )
                first[(x + 1) * stride + y + 1] = -1
    return clean


@njit
def _apart(
    cell: np.ndarray, direction: np.ndarray, offset: np.ndarray, a: int, b: int
) -> float:  # pragma: no cover (compiled)
    """How far apart the centres of squares `a` and `b` are, along the farther axis."""
    ax = (
        cell[a, 0]
        + offset[a] * STEPS[direction[a], 0]
        - cell[b, 0]
        - offset[b] * STEPS[direction[b], 0]
    )
    ay = (
        cell[a, 1]
        + offset[a] * STEPS[direction[a], 1]
        - cell[b, 1]
        - offset[b] * STEPS[direction[b], 1]
    )
    return max(abs(ax), abs(ay))


@njit
def _rests_on(
    cell: np.ndarray, offset: np.ndarray, present: np.ndarray, r: int, key: int, stride: int
) -> bool:  # pragma: no cover (compiled)
    """Whether robot `r` rests on the cell of `key` (`overlaps`' keys)."""
    x, y = cell[r, 0], cell[r, 1]
    return bool(present[r]) and offset[r] <= 0 and (x + 1) * stride + y + 1 == key


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

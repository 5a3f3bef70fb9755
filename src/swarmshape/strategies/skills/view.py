"""What a robot senses around it, cell by cell.

Offsets are sensed from where the robot is now, which under way lies between two cells; adding
its progress along its heading makes them relative to the cell it is leaving, its own cell.
Rounded, they say which cell each neighbour is on (noise of up to half a cell is absorbed).
"""

from __future__ import annotations

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Perception

SILENCE = 10
"""Steps a robot sees a neighbour it does not hear before it takes it for stalled: a stalled
robot is silent and holds its cell for good, while a live one goes unheard that long only
with chance ``msg_loss ** SILENCE``."""


class View:
    """Per robot, the square of cells within `reach` round its own cell: which hold something
    it senses (`taken`), and the entry (index into the perception's arrays) of the neighbour
    on each (`who`, -1 where none). A neighbour known to be under way (`coming`: its heading
    per entry, 0 if at rest or unknown) takes the cell it is coming to as well."""

    def __init__(self, sense: Perception, reach: int, coming: np.ndarray | None = None) -> None:
        n, r = len(sense), reach
        self.reach = r
        side = 2 * r + 1
        # the squares inside a border of free cells, where a look beyond them lands (`at`);
        # entries as int32, half the memory a step reads them from (its cache misses cost more
        # than the reads: a perception holds far fewer than 2**31 entries)
        self.bordered_taken = np.zeros((n, side + 2, side + 2), dtype=bool)
        self.bordered_who = np.full((n, side + 2, side + 2), -1, dtype=np.int32)
        self.taken = self.bordered_taken[:, 1:-1, 1:-1]
        self.who = self.bordered_who[:, 1:-1, 1:-1]
        if coming is None:
            coming = np.zeros(len(sense.owner), dtype=np.int64)
        self.cells = np.empty((len(sense.owner), 2), dtype=np.int64)
        """Each entry's cell relative to its robot's own cell."""
        _mark(sense.offset, sense.progress, sense.heading, sense.owner, coming, r,
              self.cells, self.bordered_taken, self.bordered_who)  # fmt: skip

    def taken_of(self, robots: np.ndarray) -> np.ndarray:
        """`taken`'s squares of `robots` only ``(k, side, side)``."""
        return _inner(self.bordered_taken, robots)

    def who_of(self, robots: np.ndarray) -> np.ndarray:
        """`who`'s squares of `robots` only ``(k, side, side)``."""
        return _inner(self.bordered_who, robots)

    def at(self, robots: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whether each robot senses something on a cell relative to its own, and the entry of
        the neighbour there (-1: none). Cells beyond its window are free as far as it knows."""
        taken = np.empty(len(robots), dtype=bool)
        who = np.empty(len(robots), dtype=np.int64)
        _look(self.bordered_taken, self.bordered_who, robots, cells, self.reach, taken, who)
        return taken, who


def _inner(bordered: np.ndarray, robots: np.ndarray) -> np.ndarray:
    """The squares of `robots` without their border, gathered by np.take from the contiguous
    bordered ones: numpy 2.4's ``taken[robots]`` copies row by row, and np.take of `taken`, a
    view, copies all of it first (0.3 ms a call at 10,000 robots)."""
    return np.take(bordered, robots, axis=0)[:, 1:-1, 1:-1]


@njit
def _mark(
    offset: np.ndarray,
    progress: np.ndarray,
    heading: np.ndarray,
    owner: np.ndarray,
    coming: np.ndarray,
    reach: int,
    cells: np.ndarray,
    taken: np.ndarray,
    who: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """`View`'s squares in one pass over the entries, then one over those coming: a dozen
    numpy passes over a 10,000-robot swarm's 190,000 entries cost `mean-shift` a sixth of its
    step. An entry marks its cell, and then its cell ahead if it is under way; a later mark on
    the same cell wins. The marks are written here, not by a kernel called per mark: that
    call counts references to the arrays passed to it, and made the pass three times as slow
    (2.5 ms against 0.7 ms at step 100 of `mean-shift` on the 10,000-robot S)."""
    m = len(owner)
    for entry in range(m):
        robot = owner[entry]
        for axis in range(2):
            own = progress[robot] * STEPS[heading[robot], axis]
            cells[entry, axis] = np.int64(np.rint(offset[entry, axis] + own))

    def mark(entry: int, way: int) -> None:
        x, y = cells[entry, 0] + STEPS[way, 0], cells[entry, 1] + STEPS[way, 1]
        if abs(x) <= reach and abs(y) <= reach:
            taken[owner[entry], x + reach + 1, y + reach + 1] = True
            who[owner[entry], x + reach + 1, y + reach + 1] = entry

    for entry in range(m):
        mark(entry, 0)
    for entry in range(m):  # then the cell ahead of each one coming
        if coming[entry] > 0:
            mark(entry, coming[entry])


@njit
def _look(
    taken: np.ndarray,
    who: np.ndarray,
    robots: np.ndarray,
    cells: np.ndarray,
    reach: int,
    seen: np.ndarray,
    entry: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """`View.at`: a look beyond the window lands on the border, which is free. A free cell's
    entry is -1 without reading it: the squares are out of the cache by the time a program
    looks, and the reads of `who` made the look three times as slow."""
    last = 2 * reach + 2
    for k in range(len(robots)):
        x = min(max(cells[k, 0] + reach + 1, 0), last)
        y = min(max(cells[k, 1] + reach + 1, 0), last)
        seen[k] = taken[robots[k], x, y]
        entry[k] = who[robots[k], x, y] if seen[k] else -1


def distances(blocked: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """Breadth-first through each robot's square ``(k, side, side)`` from its `sources` cells
    round its `blocked` ones (a source may be blocked itself): the fewest moves to each cell
    (-1: out of reach). Compiled: scipy's dilation, a pass of the whole stack a level, cost
    `mean-shift` a twentieth of its step."""
    steps = np.where(sources, 0, -1)
    _spread(np.ascontiguousarray(blocked), steps)
    return steps


@njit
def _spread(blocked: np.ndarray, steps: np.ndarray) -> None:  # pragma: no cover (compiled)
    """`distances`, robot by robot, by a queue. Scanning the whole square once a level cost a
    robot side x side x 4 cells a level; this visits each cell once."""
    side = blocked.shape[1]
    queue = np.empty(side * side, dtype=np.int64)
    for r in range(blocked.shape[0]):
        tail = 0
        for x in range(side):
            for y in range(side):
                if steps[r, x, y] == 0:
                    queue[tail] = x * side + y
                    tail += 1
        head = 0
        while head < tail:
            x, y = queue[head] // side, queue[head] % side
            head += 1
            for direction in range(1, 5):
                tx, ty = x + STEPS[direction, 0], y + STEPS[direction, 1]
                if not (0 <= tx < side and 0 <= ty < side) or blocked[r, tx, ty]:
                    continue
                if steps[r, tx, ty] < 0:
                    steps[r, tx, ty] = steps[r, x, y] + 1
                    queue[tail] = tx * side + ty
                    tail += 1

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
        own = sense.progress[:, None] * STEPS[sense.heading]
        self.cells = np.rint(sense.offset + own[sense.owner]).astype(np.int64)
        """Each entry's cell relative to its robot's own cell."""
        side = 2 * r + 1
        # the squares inside a border of free cells, where a look beyond them lands (`at`)
        self._taken = np.zeros((n, side + 2, side + 2), dtype=bool)
        self._who = np.full((n, side + 2, side + 2), -1, dtype=np.int64)
        self.taken = self._taken[:, 1:-1, 1:-1]
        self.who = self._who[:, 1:-1, 1:-1]
        entries = np.arange(len(sense.owner))
        near = (np.abs(self.cells) <= r).all(axis=1)
        self._mark(sense.owner[near], self.cells[near], entries[near])
        if coming is not None:
            going = np.flatnonzero(coming > 0)
            ahead = self.cells[going] + STEPS[coming[going]]
            near = (np.abs(ahead) <= r).all(axis=1)
            self._mark(sense.owner[going[near]], ahead[near], going[near])

    def _mark(self, robots: np.ndarray, cells: np.ndarray, entries: np.ndarray) -> None:
        r = self.reach
        self.taken[robots, cells[:, 0] + r, cells[:, 1] + r] = True
        self.who[robots, cells[:, 0] + r, cells[:, 1] + r] = entries

    def at(self, robots: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whether each robot senses something on a cell relative to its own, and the entry of
        the neighbour there (-1: none). Cells beyond its window are free as far as it knows."""
        bordered = 2 * self.reach + 3  # the side of a square with its border
        at = cells + (self.reach + 1)
        np.minimum(np.maximum(at, 0, out=at), bordered - 1, out=at)
        # one flat index for both gathers: three index arrays each cost three times as much
        flat = (robots * bordered + at[:, 0]) * bordered + at[:, 1]
        return self._taken.reshape(-1).take(flat), self._who.reshape(-1).take(flat)


def paths(blocked: np.ndarray, sources: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Breadth-first through each robot's square ``(k, side, side)`` from its `sources` cells
    round its `blocked` ones (a source may be blocked itself): the fewest moves to each cell
    (-1: out of reach) and the first move of a shortest way there, the way of the cell it is
    entered from by the first move, in move order, that enters it from one a move nearer (0
    at a source). Compiled: scipy's dilation, a pass of the whole stack a level, cost
    `mean-shift` a twentieth of its step."""
    steps = np.where(sources, 0, -1)
    way = np.zeros(blocked.shape, dtype=np.int64)
    _spread(np.ascontiguousarray(blocked), steps, way)
    return steps, way


@njit
def _spread(
    blocked: np.ndarray, steps: np.ndarray, way: np.ndarray
) -> None:  # pragma: no cover (compiled)
    """`paths`, robot by robot: the distances by a queue, then the ways in the queue's order
    (each cell's after those of the cells a move nearer). Scanning the whole square once a
    level cost a robot side x side x 4 cells a level; this visits each cell once."""
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
        for k in range(tail):
            x, y = queue[k] // side, queue[k] % side
            if steps[r, x, y] == 0:
                continue
            for direction in range(1, 5):
                fx, fy = x - STEPS[direction, 0], y - STEPS[direction, 1]
                if 0 <= fx < side and 0 <= fy < side and steps[r, fx, fy] == steps[r, x, y] - 1:
                    way[r, x, y] = direction if steps[r, x, y] == 1 else way[r, fx, fy]
                    break

"""Which way a moving agent should step next to reach its target.

`straight_preferences` is the concurrent movers' rule: of the (at most two) directions that
bring an agent closer, keep going the way it goes, else take the L-shaped path that crosses
fewer cells of the shape.
`FieldPlanner` is the paper's navigator for few movers: a breadth-first distance field from the
target over the cells not blocked by resting agents or seeds, followed downhill. Fields are
cached per agent and recomputed when the agent is told its view is stale (it got blocked).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.motion import STEPS, inside, rows
from swarmshape.core.snapshot import Snapshot

WINDOW_MARGIN = 6
"""Cells around an agent and its goal searched first for a path."""

STRAIGHT_BONUS = 0.2
LONG_AXIS_BONUS = 0.1
"""Tie-breaks among equally short steps: keep going straight (no stop to turn), else close the
longer remaining axis first, so paths are L-shaped rather than staircases."""


class CrossingCounter:
    """How many shape cells each of the two L-shaped paths between two cells crosses.

    Prefix sums along rows and columns make every count O(1), for any number of agents.
    """

    def __init__(self, shape_mask: np.ndarray) -> None:
        width, height = shape_mask.shape  # counts up to 25,000,000 cells: int32 will do
        self._along_x = np.zeros((width + 1, height), dtype=np.int32)
        self._along_y = np.zeros((width, height + 1), dtype=np.int32)
        np.cumsum(shape_mask, axis=0, dtype=np.int32, out=self._along_x[1:])
        np.cumsum(shape_mask, axis=1, dtype=np.int32, out=self._along_y[:, 1:])

    def _row(self, y: np.ndarray, xa: np.ndarray, xb: np.ndarray) -> np.ndarray:
        low, high = np.minimum(xa, xb), np.maximum(xa, xb)
        return self._along_x[high + 1, y] - self._along_x[low, y]

    def _column(self, x: np.ndarray, ya: np.ndarray, yb: np.ndarray) -> np.ndarray:
        low, high = np.minimum(ya, yb), np.maximum(ya, yb)
        return self._along_y[x, high + 1] - self._along_y[x, low]

    def x_first_crosses_less(
        self, origin: np.ndarray, goal: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """True where going along x first crosses fewer shape cells than y first."""
        (x0, y0), (x1, y1) = origin.T, goal.T
        x_first = self._row(y0, x0, x1) + self._column(x1, y0, y1)
        y_first = self._column(x0, y0, y1) + self._row(y1, x0, x1)
        return x_first < y_first, x_first == y_first


def straight_preferences(
    origin: np.ndarray, goal: np.ndarray, current: np.ndarray, crossings: CrossingCounter
) -> tuple[np.ndarray, np.ndarray]:
    """Preferred and second direction index (0 = none) from `origin` toward `goal`.

    Keep going the way the agent goes; else take the L-shaped path through fewer shape cells
    (settled agents there would have to swap), else close the longer gap first.
    """
    dx, dy = (goal - origin).T
    along_x = np.where(dx > 0, 1, np.where(dx < 0, 2, 0))
    along_y = np.where(dy > 0, 3, np.where(dy < 0, 4, 0))
    keep_x = (current == along_x) & (along_x > 0)
    keep_y = (current == along_y) & (along_y > 0)
    x_first = keep_x
    turning = np.flatnonzero(~keep_x & ~keep_y & (along_x > 0) & (along_y > 0))
    if len(turning):
        fewer, tie = crossings.x_first_crosses_less(rows(origin, turning), rows(goal, turning))
        longer = np.abs(dx[turning]) >= np.abs(dy[turning])
        x_first[turning] = np.where(tie, longer, fewer)
    first = np.where(x_first, along_x, along_y)
    second = np.where(x_first, along_y, along_x)
    return np.where(first > 0, first, second), np.where(first > 0, second, 0)


class FieldPlanner:
    """Breadth-first distance fields over the arena, one per agent that needs a path.

    Fields live as rows of one array (row 0 is all infinity: "no field"), so looking up the
    neighbour distances of many agents is a single indexing operation.
    """

    def __init__(self, size: tuple[int, int], agents: int) -> None:
        self.size = size
        width, height = size
        self._rows = np.full((1, width * height), np.inf)  # more as agents need them:
        self._row_of = np.zeros(agents, dtype=np.int64)  # each is a float per arena cell
        self._spare: list[int] = []

    @staticmethod
    def field(goal: np.ndarray, passable: np.ndarray) -> np.ndarray:
        """Steps from every cell to `goal` through `passable` cells, shaped like `passable`
        (inf where no path leads; `goal` itself is 0 whether or not it is passable)."""
        return _steps_to(np.ascontiguousarray(passable), int(goal[0]), int(goal[1]))

    def plan(self, agent: int, cell: np.ndarray, goal: np.ndarray, views: list[np.ndarray]) -> None:
        """Keep a field for `agent`: the first passable view in which `goal` is reachable.

        Each view is searched first in a window around the agent and its goal, which is all
        a detour around a small obstacle needs, and in the whole arena only if that fails.
        """
        if self._row_of[agent] == 0:
            if not self._spare:
                grown = len(self._rows)
                self._rows = np.vstack([self._rows, np.full_like(self._rows, np.inf)])
                self._spare = list(range(grown, len(self._rows)))
            self._row_of[agent] = self._spare.pop()
        row = self._rows[self._row_of[agent]].reshape(self.size)
        low = np.maximum(np.minimum(cell, goal) - WINDOW_MARGIN, 0)
        high = np.minimum(np.maximum(cell, goal) + WINDOW_MARGIN + 1, self.size)
        window = (slice(low[0], high[0]), slice(low[1], high[1]))
        for passable in views:
            for part in (window, (slice(None), slice(None))):
                offset = np.array([part[0].start or 0, part[1].start or 0])
                row[...] = np.inf
                row[part] = self.field(goal - offset, passable[part])
                if np.isfinite(row[cell[0], cell[1]]):
                    return

    def snapshot(self) -> dict[str, Any]:
        spare = np.array(self._spare, dtype=np.int64)
        return {"rows": self._rows, "row_of": self._row_of, "spare": spare}

    def restore(self, saved: Snapshot) -> None:
        """Fields as saved (they decide paths, so a resumed run must keep them)."""
        width, height = self.size
        rows = saved.array("rows", np.float64, (None, width * height), 0, finite=False)
        if len(rows) == 0 or np.isfinite(rows[0]).any():
            raise saved.error("rows", "lacks its first, empty field")
        self._rows = rows
        self._row_of = saved.array("row_of", np.int64, self._row_of.shape, 0, len(rows) - 1)
        self._spare = saved.array("spare", np.int64, (None,), 1, len(rows) - 1).tolist()

    def planned(self, agents: np.ndarray) -> np.ndarray:
        return self._row_of[agents] > 0

    def remaining(self, agents: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """Steps from `cells` to each agent's goal along its field (inf where none leads)."""
        return self._rows[self._row_of[agents], cells[:, 0] * self.size[1] + cells[:, 1]]

    def forget(self, agents: np.ndarray) -> None:
        rows = self._row_of[agents]
        self._spare.extend(np.unique(rows[rows > 0]).tolist())
        self._row_of[agents] = 0

    def directions(
        self, agents: np.ndarray, cells: np.ndarray, goals: np.ndarray, current: np.ndarray
    ) -> np.ndarray:
        """Direction index of the best downhill step from each agent's `cells`.

        0 where no step leads closer, or where the agent has no field (it must plan first).
        """
        if len(agents) == 0:
            return np.zeros(0, dtype=np.int64)
        rows = self._row_of[agents][:, None]
        neighbours = cells[:, None, :] + STEPS[None, 1:, :]
        valid = inside(neighbours.reshape(-1, 2), self.size).reshape(-1, 4)
        flat = np.where(valid, neighbours[..., 0] * self.size[1] + neighbours[..., 1], 0)
        downhill = np.where(valid, self._rows[rows, flat], np.inf)
        here = self._rows[rows[:, 0], cells[:, 0] * self.size[1] + cells[:, 1]]
        remaining = np.abs(goals - cells)
        long_axis = np.where(remaining[:, 0] >= remaining[:, 1], 0, 1)
        axis_of = np.array([0, 0, 1, 1])
        score = downhill.copy()
        score -= STRAIGHT_BONUS * (np.arange(1, 5)[None, :] == current[:, None])
        score -= LONG_AXIS_BONUS * (axis_of[None, :] == long_axis[:, None])
        best = np.argmin(score, axis=1)
        improves = downhill[np.arange(len(agents)), best] < here
        return np.where(improves, best + 1, 0)


@njit
def _steps_to(passable: np.ndarray, x: int, y: int) -> np.ndarray:  # pragma: no cover (compiled)
    """Breadth first from cell ``(x, y)`` through side neighbours that are both `passable`.
    Built as a sparse graph for scipy's shortest paths each time, the same field took 12 times
    as long (7.8 ms against 0.65 on 21,600 cells): 36 s of the 50 s that 300 steps of a
    100-group scenario took."""
    width, height = passable.shape
    steps = np.full((width, height), np.inf)
    steps[x, y] = 0.0
    if not passable[x, y]:
        return steps
    queue = np.empty(width * height, dtype=np.int64)
    queue[0], head, tail = x * height + y, 0, 1
    while head < tail:
        cx, cy = queue[head] // height, queue[head] % height
        head += 1
        for nx, ny in ((cx - 1, cy), (cx + 1, cy), (cx, cy - 1), (cx, cy + 1)):
            if (
                0 <= nx < width
                and 0 <= ny < height
                and passable[nx, ny]
                and steps[nx, ny] > steps[cx, cy] + 1
            ):
                steps[nx, ny] = steps[cx, cy] + 1
                queue[tail] = nx * height + ny
                tail += 1
    return steps

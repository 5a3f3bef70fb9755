"""What one robot can know: its neighbours within a sensing radius, their last messages, its
own odometry, and the shape's bitmap in its seed frame. Built for all robots at once.

A local program (`swarmshape.core.local`) sees only a `Perception`, never the swarm. Neighbour
lists are CSR rows: robot ``i``'s entries are ``start[i]:start[i + 1]`` of every per-entry
array (``owner`` repeats ``i`` over them). Offsets and moves are in the robot's seed-frame
axes, as if every robot had a compass aligned with its seeds' L, so a rotated or translated
scenario is the same problem to a program. Noise is drawn from the run's one generator.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from swarmshape.core.compiled import njit
from swarmshape.core.options import checked, option
from swarmshape.core.shape import Pose


@dataclass(frozen=True)
class Senses:
    """How well robots sense and talk; the names match Kilombo's and ARGoS's knobs."""

    radius: float = option(
        3.0,
        "cells within which a robot senses and hears others (a Kilobot reaches about three bodies)",
        name="sense_radius",
        at_least=1.0,
        at_most=16.0,
    )
    distance_noise: float = option(
        0.0, "standard deviation of each sensed offset, in cells", at_least=0.0, at_most=1.0
    )
    msg_loss: float = option(
        0.0,
        "chance per step that the link between two neighbours fails, both ways; Kilombo's "
        "msgSuccessRate is 1 - this",
        at_least=0.0,
        below=1.0,
    )

    def __post_init__(self) -> None:
        checked(self)

    def reach(self) -> np.ndarray:
        """Cell offsets ``(k, 2)`` within the radius, nearest first, without ``(0, 0)``."""
        r = int(self.radius)
        grid = np.mgrid[-r : r + 1, -r : r + 1].reshape(2, -1).T
        distance = np.hypot(grid[:, 0], grid[:, 1])
        keep = (distance <= self.radius) & (distance > 0)
        order = np.lexsort((grid[keep, 1], grid[keep, 0], distance[keep]))
        return grid[keep][order]


@dataclass(frozen=True, eq=False)
class Blueprint:
    """The shapes, as each robot knows them: every group's cells in its seed frame."""

    cells: tuple[np.ndarray, ...]
    """Per group, its shape's frame cells ``(k, 2)`` in row-major order (the same list every
    robot of the group holds)."""
    _numbers: Boxes = field(repr=False)
    _inside: Boxes = field(repr=False)
    _digests: np.ndarray = field(repr=False)

    @classmethod
    def of(cls, frame_cells: list[np.ndarray]) -> Blueprint:
        boxes = []
        for cells in frame_cells:  # each box with a border of -1, where lookups off it land
            low = (cells.min(axis=0) if len(cells) else np.zeros(2, dtype=np.int64)) - 1
            high = (cells.max(axis=0) + 1 if len(cells) else np.zeros(2, dtype=np.int64)) + 1
            grid = np.full(high - low, -1, dtype=np.int64)
            grid[cells[:, 0] - low[0], cells[:, 1] - low[1]] = np.arange(len(cells))
            boxes.append((low, grid))
        digests = [zlib.crc32(np.ascontiguousarray(c, dtype=np.int64).data) for c in frame_cells]
        inside = Boxes([(low, grid >= 0) for low, grid in boxes])
        return cls(
            tuple(frame_cells), _numbers=Boxes(boxes), _inside=inside, _digests=np.array(digests)
        )

    def digest(self, groups: np.ndarray) -> np.ndarray:
        """A checksum of each entry's group's shape (CRC-32 of its cells, not negative): a robot
        that keeps the last one it saw knows when its shape changed."""
        return self._digests[groups].astype(np.int64)

    def count(self, groups: np.ndarray) -> np.ndarray:
        """How many cells the shape of each entry's group has."""
        return np.array([len(c) for c in self.cells], dtype=np.int64)[groups]

    def number(self, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
        """The number of each frame cell ``(k, 2)`` in its group's shape, or -1 (not in it)."""
        return self._numbers.at(groups, frame)

    def contains(self, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
        """Whether each frame cell ``(k, 2)`` is in the shape of the matching group."""
        return self.number(groups, frame) >= 0

    def contains_around(self, groups: np.ndarray, frame: np.ndarray, reach: int) -> np.ndarray:
        """`contains` over the square of half-width `reach` round each frame cell ``(k, 2)``:
        ``(k, side, side)``, the frame cell at ``[reach, reach]`` (see `Boxes.around`). A byte
        a cell: squares of cell numbers, eight bytes a cell compared with 0, cost `mean-shift`
        3 ms a step at 10,000 robots, not 0.5."""
        return self._inside.around(groups, frame, reach)

    def cell(self, groups: np.ndarray, numbers: np.ndarray) -> np.ndarray:
        """The frame cell numbered `numbers` (row-major) in each entry's group's shape."""
        out = np.zeros((len(groups), 2), dtype=np.int64)
        for group, cells in enumerate(self.cells):
            mine = groups == group
            out[mine] = cells[numbers[mine]]
        return out


class Boxes:
    """Per group, a grid of values over a box of its seed frame whose border holds the value of
    every cell beyond it (depths, cell numbers), looked up for many robots at once.

    The groups' grids are stacked into one array, each padded out with its own border, so a
    lookup is one clip and one gather whatever the groups: local programs look up cells many
    times a step, and a loop over groups cost more than all the rest of the lookup."""

    def __init__(self, boxes: list[tuple[np.ndarray, np.ndarray]]) -> None:
        self.boxes = tuple(boxes)
        """Per group, the frame cell of its grid's corner and the grid."""
        size = np.max([grid.shape for _, grid in boxes], axis=0)
        self.low = np.array([low for low, _ in boxes], dtype=np.int64).reshape(-1, 2)
        self.grids = np.stack([np.pad(grid, [(0, size[0] - grid.shape[0]),
                                             (0, size[1] - grid.shape[1])], mode="edge")
                               for _, grid in boxes])  # fmt: skip
        self.top = size - 1

    def at(self, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
        """The value at each frame cell ``(k, 2)`` in the grid of its entry's group."""
        return _box_values(self.grids, self.low, self.top, groups, frame)

    def around(self, groups: np.ndarray, frame: np.ndarray, reach: int) -> np.ndarray:
        """The values over the square of half-width `reach` round each frame cell ``(k, 2)``
        ``(k, side, side)``, in its entry's group's grid: what `at` gives at every offset,
        for a program that looks a cell and its neighbours up many times a step."""
        return _box_squares(self.grids, self.low, self.top, groups, frame, reach)


@njit
def _box_values(
    grids: np.ndarray, low: np.ndarray, top: np.ndarray, groups: np.ndarray, frame: np.ndarray
) -> np.ndarray:  # pragma: no cover (compiled)
    """`Boxes.at` in one pass: numpy's subtract, two clips and a three-way gather cost a local
    program a sixth of its step (the 476-robot S under `mean-shift`)."""
    out = np.empty(len(groups), dtype=grids.dtype)
    for i in range(len(groups)):
        g = groups[i]
        x = min(max(frame[i, 0] - low[g, 0], 0), top[0])
        y = min(max(frame[i, 1] - low[g, 1], 0), top[1])
        out[i] = grids[g, x, y]
    return out


@njit
def _box_squares(
    grids: np.ndarray,
    low: np.ndarray,
    top: np.ndarray,
    groups: np.ndarray,
    frame: np.ndarray,
    reach: int,
) -> np.ndarray:  # pragma: no cover (compiled)
    """`Boxes.around`, square by square."""
    side = 2 * reach + 1
    out = np.empty((len(groups), side, side), dtype=grids.dtype)
    for i in range(len(groups)):
        g = groups[i]
        for a in range(side):
            x = min(max(frame[i, 0] + a - reach - low[g, 0], 0), top[0])
            for b in range(side):
                y = min(max(frame[i, 1] + b - reach - low[g, 1], 0), top[1])
                out[i, a, b] = grids[g, x, y]
    return out


@dataclass(frozen=True, eq=False)
class Perception:
    """One step's senses of every robot (robots ``0..n-1``; entries in CSR rows by robot)."""

    number: np.ndarray
    """Each robot's number in its group, 0 up: a unique ID it was built with."""
    group: np.ndarray
    """Each robot's group (an index into `blueprint.cells`)."""
    ready: np.ndarray
    """At rest on a cell centre: a move it asks for, any way, starts now."""
    heading: np.ndarray
    """The direction it is moving in (a move index, seed-frame axes), 0 at rest."""
    cruising: np.ndarray
    """Under way with its next cell reserved and no further: a move straight on (`heading`)
    asked for now goes on without braking. Asked for nothing, it brakes and stops on that cell
    (it cannot turn while under way)."""
    progress: np.ndarray
    """How far, in cells, it has come from its cell's centre along `heading` (its odometer's
    fraction of a cell; 0 at rest): its neighbours' offsets are from where it is now."""
    moved: np.ndarray
    """Odometry: the whole cells each robot moved since the last step ``(n, 2)``."""
    start: np.ndarray
    """CSR row starts ``(n + 1,)``."""
    owner: np.ndarray
    """The robot each entry belongs to."""
    offset: np.ndarray
    """The neighbour's centre relative to the robot's, in cells ``(m, 2)`` (noisy if set)."""
    seed: np.ndarray
    """The neighbour is a seed: it never moves, and broadcasts `seed_frame`."""
    kin: np.ndarray
    """The neighbour belongs to the robot's group (its messages are in the same language)."""
    heard: np.ndarray
    """Its message came through this step."""
    message: np.ndarray
    """The neighbour's last broadcast ``(m, k)`` where heard, zeros where not (and for seeds)."""
    seed_frame: np.ndarray
    """A heard seed's frame cell ``(m, 2)`` (zeros elsewhere)."""
    blueprint: Blueprint
    step: int
    radius: float
    """How far, in cells, every robot senses and hears (the run's sensing radius)."""

    def __len__(self) -> int:
        return len(self.number)


def quarter_turns(poses: list[Pose]) -> np.ndarray:
    """Per group, the quarter turns from its seed frame's axes to the world's."""
    return np.array([p.rotation // 90 % 4 for p in poses], dtype=np.int64)


def turn(vectors: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """Rotate integer or float vectors ``(k, 2)`` by per-row quarter turns, clockwise on screen."""
    out = np.array(vectors, dtype=np.result_type(vectors, np.int64), copy=True)
    if not turns.any():  # the usual case: every seed frame has the world's axes
        return out
    for _ in range(3):
        rows = turns > 0
        out[rows] = np.column_stack([-out[rows, 1], out[rows, 0]])
        turns = np.where(rows, turns - 1, 0)
    return out


def neighbours(
    cell: np.ndarray,
    seeds: np.ndarray,
    size: tuple[int, int],
    reach: np.ndarray,
    present: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(start, owner, other)``: for every robot, the robots and seeds (``n + seed index``)
    whose cells lie within `reach`, in CSR rows ordered by the order of `reach`. Robots not
    `present` (removed by a fault) neither sense nor are sensed. One gather of every robot's
    every offset from a padded grid of who is where, never a loop over robots."""
    here = np.arange(len(cell)) if present is None else np.flatnonzero(present)
    return _neighbours(cell, seeds, size[0], size[1], reach, here)


@njit
def _neighbours(
    cell: np.ndarray, seeds: np.ndarray, width: int, height: int, reach: np.ndarray,
    here: np.ndarray,
) -> tuple[
    npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64]
]:  # pragma: no cover (compiled)  # fmt: skip
    """`neighbours` on a padded grid of who is where, in one pass robot by robot. Every
    offset's occupant is written and the entry kept by adding whether it is someone: a branch
    per offset would be mispredicted about a third of the time, which made this pass three
    times slower in a run than the same call repeated (the predictor learns a repeated call)."""
    n = len(cell)
    r = 0
    for k in range(len(reach)):
        r = max(r, abs(reach[k, 0]), abs(reach[k, 1]))
    stride = height + 2 * r
    who = np.full((width + 2 * r) * stride, -1)
    for robot in here:
        who[(cell[robot, 0] + r) * stride + cell[robot, 1] + r] = robot
    for s in range(len(seeds)):
        who[(seeds[s, 0] + r) * stride + seeds[s, 1] + r] = n + s
    shift = reach[:, 0] * stride + reach[:, 1]
    start = np.zeros(n + 1, dtype=np.int64)
    found = np.empty(len(here) * len(shift) + 1, dtype=np.int64)
    entry = 0
    for robot in here:
        base = (cell[robot, 0] + r) * stride + cell[robot, 1] + r
        first = entry
        for d in shift:
            found[entry] = who[base + d]
            entry += found[entry] >= 0
        start[robot + 1] = entry - first
    for robot in range(n):
        start[robot + 1] += start[robot]
    other = found[:entry].copy()
    owner = np.empty(entry, dtype=np.int64)
    for robot in here:
        owner[start[robot] : start[robot + 1]] = robot
    return start, owner, other

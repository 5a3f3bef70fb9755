"""A shape in its seed frame: which cells it has, where the seeds sit, and how it is placed.

Frame coordinates are ``(x, y) = (col, row)`` of the bitmap, y growing downward as in the image.
The seed robots occupy fixed frame cells just outside the shape's top-left corner; placing the
frame with a `Pose` moves and rotates the shape and its seeds together.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from swarmshape.core.grid import crop, resample
from swarmshape.errors import InputError

SEED_CELLS = np.array([[-1, -1], [0, -1], [1, -1], [-1, 0]])
"""Four seeds in an L: the long arm marks the frame's x axis, the short one its y axis."""

SEED_SIDES = np.array(
    [[0, 0], [1, 0], [2, -1], [-2, -1], [-1, -2], [0, -2], [1, -2], [-2, 0], [-1, 1]]
)
"""The frame cells that share a side with a seed (and are not one)."""


MAX_ARENA_CELLS = 25_000_000
"""The largest arena, in cells (a cap that keeps memory bounded; no side is longer)."""


JUMP = 1.2
"""How far above the side that the area alone says fits `Shape.fitted` starts looking down
(a tenth in side, a fifth in count)."""


def frozen(array: np.ndarray) -> np.ndarray:
    """`array`, made read-only (an array of a shape or a world is never written after it is
    made)."""
    array.flags.writeable = False
    return array


class ShapeError(InputError):
    """A shape or pose that cannot be used; the message says why."""


@dataclass(frozen=True)
class Pose:
    """Where the seed frame sits in the arena: origin cell and rotation (clockwise on screen)."""

    x: int = 0
    y: int = 0
    rotation: int = 0

    def __post_init__(self) -> None:
        if self.rotation % 90:
            raise ShapeError(f"rotation must be a multiple of 90 degrees, got {self.rotation}")
        if max(abs(self.x), abs(self.y)) > MAX_ARENA_CELLS:  # and so fits int64 arithmetic
            raise ShapeError(
                f"pose ({self.x}, {self.y}) lies beyond any arena (no side is longer than "
                f"{MAX_ARENA_CELLS:,} cells)"
            )

    def to_world(self, frame_cells: np.ndarray) -> np.ndarray:
        """Map integer frame cells to world cells (the unit squares rotate about the origin)."""
        return _turn(frame_cells, self.rotation // 90) + np.array([self.x, self.y])

    def to_frame(self, world_cells: np.ndarray) -> np.ndarray:
        """The inverse of `to_world`."""
        return _turn(np.asarray(world_cells) - np.array([self.x, self.y]), -self.rotation // 90)


def _turn(cells: np.ndarray, quarter_turns: int) -> np.ndarray:
    """Rotate unit cells about the origin by quarter turns, clockwise on screen (y down)."""
    centres = np.asarray(cells, dtype=np.float64).reshape(-1, 2) + 0.5
    for _ in range(quarter_turns % 4):
        centres = np.column_stack([-centres[:, 1], centres[:, 0]])
    return np.floor(centres).astype(np.int64)


@dataclass(frozen=True, eq=False)
class Shape:
    """A boolean grid, the scale it was shrunk to (1.0 as drawn), and where its top-left cell
    sits in the seed frame (a painted shape may start anywhere around the seeds)."""

    grid: np.ndarray
    scale: float = 1.0
    origin: tuple[int, int] = (0, 0)

    def __post_init__(self) -> None:
        # its own read-only copy: a shape is a value, which neither its maker nor a plug-in
        # that is shown it can change under a running swarm
        object.__setattr__(self, "grid", frozen(np.array(self.grid, dtype=bool)))

    @classmethod
    def from_cells(cls, cells: np.ndarray) -> Shape:
        """The shape made of these frame cells ``(k, 2)``, cropped, at their own origin."""
        low = cells.min(axis=0)
        width, height = cells.max(axis=0) - low + 1
        grid = np.zeros((height, width), dtype=bool)
        grid[cells[:, 1] - low[1], cells[:, 0] - low[0]] = True
        return cls(grid, origin=(int(low[0]), int(low[1])))

    @property
    def cells(self) -> np.ndarray:
        """Frame cells ``(k, 2)`` of the shape as ``(x, y)``, in row-major order."""
        rows, cols = np.nonzero(self.grid)
        return np.column_stack([cols, rows]).astype(np.int64) + np.array(self.origin)

    def seeded(self) -> Shape:
        """This shape if it touches its seeds, else moved so that the first cell of its top row
        sits in the seed L's corner: a swarm that grows from its seeds can reach only a shape
        that touches them (a star's or a disc's top-left corner is empty). Central strategies
        keep the corner placement: there the seed L stays clear of the robots coming in."""
        rows, cols = np.nonzero(self.grid)
        if not len(rows) or self._touches_seeds():
            return self
        return Shape(self.grid, self.scale, (-int(cols[0]), -int(rows[0])))

    def solid(self) -> Shape:
        """The part of this shape a swarm that grows outward from its seeds can form: the
        `seeded` shape's cells joined to the seeds by cell sides, with every hole that they and
        the seeds enclose filled (Rubenstein et al.'s robots join only the edge of what is
        built)."""
        from scipy import ndimage

        cells = np.concatenate([SEED_CELLS, self.seeded().cells])
        low = cells.min(axis=0) - 1
        size = cells.max(axis=0) - low + 2
        grid = np.zeros((size[1], size[0]), dtype=bool)
        grid[cells[:, 1] - low[1], cells[:, 0] - low[0]] = True
        pieces, _ = ndimage.label(grid)
        seeded = pieces == pieces[SEED_CELLS[0, 1] - low[1], SEED_CELLS[0, 0] - low[0]]
        built = ndimage.binary_fill_holes(seeded)
        built[SEED_CELLS[:, 1] - low[1], SEED_CELLS[:, 0] - low[0]] = False
        rows, cols = np.nonzero(built)
        if not len(rows):
            return self
        solid = Shape.from_cells(np.column_stack([cols, rows]) + low)
        return Shape(solid.grid, self.scale, solid.origin)

    def sealed(self, radius: float = 0.0) -> np.ndarray:
        """The frame cells ``(k, 2)`` of pieces of the shape (cells joined by sides) that touch
        no cell of the outside, only pockets that other pieces and the seeds enclose, and lie
        farther than `radius` (cell to cell) from every piece a robot can reach: one beside the
        outside, or within `radius` of one reached. A robot comes into such a piece only
        across another piece, from a pocket it started in, or toward an empty cell of it that
        it senses (within `radius`) from a piece it stands on."""
        from scipy import ndimage

        cells = np.concatenate([SEED_CELLS, self.cells])
        low = cells.min(axis=0) - 1
        size = cells.max(axis=0) - low + 2
        shape = np.zeros((size[1], size[0]), dtype=bool)
        shape[self.cells[:, 1] - low[1], self.cells[:, 0] - low[0]] = True
        walls = shape.copy()
        walls[SEED_CELLS[:, 1] - low[1], SEED_CELLS[:, 0] - low[0]] = True
        free, _ = ndimage.label(~walls)
        outside = free == free[0, 0]  # the padded box's corner lies outside everything
        pieces, _ = ndimage.label(shape)
        reached = np.isin(pieces, pieces[ndimage.binary_dilation(outside) & shape]) & shape
        while radius > 0 and (shape & ~reached).any():
            # the cells within `radius` of a reached cell, and the pieces they lie in
            near = ndimage.distance_transform_edt(~reached) <= radius
            grown = np.isin(pieces, pieces[near & shape & ~reached]) & shape | reached
            if (grown == reached).all():
                break
            reached = grown
        rows, cols = np.nonzero(shape & ~reached)
        return np.column_stack([cols, rows]).astype(np.int64) + low

    def _touches_seeds(self) -> bool:
        beside = SEED_SIDES - np.array(self.origin)
        height, width = self.grid.shape
        inside = (beside >= 0).all(axis=1) & (beside[:, 0] < width) & (beside[:, 1] < height)
        return bool(self.grid[beside[inside, 1], beside[inside, 0]].any())

    @property
    def is_solid(self) -> bool:
        """Whether the shape is all its `solid` part."""
        return np.array_equal(self.solid().cells, self.cells)

    @property
    def count(self) -> int:
        return int(self.grid.sum())

    def fitted(self, agents: int) -> Shape:
        """The largest rescaled copy whose cell count does not exceed `agents`.

        The paper's answer to too few robots: form the same shape, smaller. The scale is the
        ratio of long sides, so a user can read how much was lost. A copy's count grows about
        as its side squared, so from a copy with too many cells this jumps to the side that
        puts the count `JUMP` above `agents` and goes down one side at a time from there: a
        few dozen resamplings of the grid, not one per side (2,000 cells across for 5 robots
        took 3 minutes so), and the same copy unless counts dip by more than that between
        nearby sides.
        """
        if agents < 1:
            raise ShapeError("at least one agent is needed to form a shape")
        if self.count <= agents:
            return self
        solid, long_side = self.is_solid, max(self.grid.shape)
        side = long_side - 1
        while side >= 1:
            copy = self._copy(side, solid)
            if 0 < copy.count <= agents:
                return copy
            near = math.floor(side * math.sqrt(agents / max(copy.count, 1)) * JUMP)
            side = min(side - 1, near) if copy.count > agents else side - 1
        return next(self.shrunk(0))

    def shrunk(self, start: int | None = None) -> Iterator[Shape]:
        """Ever smaller rescaled copies, largest first (from `start` cells across, or one
        fewer than this shape's), down to a single cell. A solid shape's copies stay solid
        (shrinking may close a notch into a hole or cut off a thin tip)."""
        solid, long_side = self.is_solid, max(self.grid.shape)
        for side in range(min(long_side - 1, long_side if start is None else start), 0, -1):
            smaller = self._copy(side, solid)
            if smaller.count:
                yield smaller
        yield Shape(np.ones((1, 1), dtype=bool), self.scale / long_side, self.origin)

    def _copy(self, side: int, solid: bool) -> Shape:
        """This shape rescaled to `side` cells across its long side (its `solid` part if
        `solid`); it may have no cell left."""
        long_side = max(self.grid.shape)
        smaller = Shape(
            crop(resample(self.grid.astype(np.float64), side)),
            self.scale * side / long_side,
            self.origin,
        )
        return smaller.solid() if solid and smaller.count else smaller

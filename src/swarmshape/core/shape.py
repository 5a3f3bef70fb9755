"""A shape in its seed frame: which cells it has, where the seeds sit, and how it is placed.

Frame coordinates are ``(x, y) = (col, row)`` of the bitmap, y growing downward as in the image.
The seed robots occupy fixed frame cells just outside the shape's top-left corner; placing the
frame with a `Pose` moves and rotates the shape and its seeds together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarmshape.core.grid import crop, resample
from swarmshape.errors import InputError

SEED_CELLS = np.array([[-1, -1], [0, -1], [1, -1], [-1, 0]])
"""Four seeds in an L: the long arm marks the frame's x axis, the short one its y axis."""


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
    sits in the seed frame (a painted shape may start anywhere around the seeds). Unless told,
    the seeds sit beside the first cell of the top row, so the shape touches them even when its
    top-left corner is empty (a star's): a swarm that grows from its seeds can then reach it."""

    grid: np.ndarray
    scale: float = 1.0
    origin: tuple[int, int] = None  # type: ignore[assignment]  # None: beside the seeds

    def __post_init__(self) -> None:
        if self.origin is None:
            object.__setattr__(self, "origin", _beside_seeds(self.grid))

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

    def solid(self) -> Shape:
        """The part of this shape a swarm that grows outward from its seeds can form: the cells
        joined to the seeds by cell sides, with every hole that they and the seeds enclose
        filled (Rubenstein et al.'s robots join only the edge of what is built). The shape
        itself if it touches no seed."""
        from scipy import ndimage

        cells = np.concatenate([SEED_CELLS, self.cells])
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
        ratio of long sides, so a user can read how much was lost. A solid shape stays solid
        (shrinking may close a notch into a hole or cut off a thin tip).
        """
        if agents < 1:
            raise ShapeError("at least one agent is needed to form a shape")
        if self.count <= agents:
            return self
        origin = None if self.origin == _beside_seeds(self.grid) else self.origin
        solid = self.is_solid
        long_side = max(self.grid.shape)
        fraction = self.grid.astype(np.float64)
        for side in range(long_side - 1, 0, -1):
            smaller = Shape(crop(resample(fraction, side)), self.scale * side / long_side, origin)
            if solid:
                smaller = smaller.solid()
            if 0 < smaller.count <= agents:
                return smaller
        return Shape(np.ones((1, 1), dtype=bool), self.scale / long_side, origin)


def _beside_seeds(grid: np.ndarray) -> tuple[int, int]:
    """The origin that puts the first cell of the grid's top filled row at frame cell (0, 0)."""
    rows, cols = np.nonzero(grid)
    return (-int(cols[0]), -int(rows[0])) if len(rows) else (0, 0)

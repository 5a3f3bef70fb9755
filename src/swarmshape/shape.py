"""A shape in its seed frame: which cells it has, where the seeds sit, and how it is placed.

Frame coordinates are ``(x, y) = (col, row)`` of the bitmap, y growing downward as in the image.
The seed robots occupy fixed frame cells just outside the shape's top-left corner; placing the
frame with a `Pose` moves and rotates the shape and its seeds together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarmshape.bitmap import crop, resample
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
        quarter_turns = (self.rotation // 90) % 4
        centres = np.asarray(frame_cells, dtype=np.float64) + 0.5
        for _ in range(quarter_turns):
            centres = np.column_stack([-centres[:, 1], centres[:, 0]])
        return np.floor(centres).astype(np.int64) + np.array([self.x, self.y])


@dataclass(frozen=True, eq=False)
class Shape:
    """A boolean grid and the scale it was shrunk to (1.0 when it was used as drawn)."""

    grid: np.ndarray
    scale: float = 1.0

    @property
    def cells(self) -> np.ndarray:
        """Frame cells ``(k, 2)`` of the shape as ``(x, y)``, in row-major order."""
        rows, cols = np.nonzero(self.grid)
        return np.column_stack([cols, rows]).astype(np.int64)

    @property
    def count(self) -> int:
        return int(self.grid.sum())

    def fitted(self, agents: int) -> Shape:
        """The largest rescaled copy whose cell count does not exceed `agents`.

        The paper's answer to too few robots: form the same shape, smaller. The scale is the
        ratio of long sides, so a user can read how much was lost.
        """
        if agents < 1:
            raise ShapeError("at least one agent is needed to form a shape")
        if self.count <= agents:
            return self
        long_side = max(self.grid.shape)
        fraction = self.grid.astype(np.float64)
        for side in range(long_side - 1, 0, -1):
            smaller = crop(resample(fraction, side))
            if 0 < smaller.sum() <= agents:
                return Shape(smaller, self.scale * side / long_side)
        return Shape(np.ones((1, 1), dtype=bool), self.scale / long_side)

"""The arena's cells and who holds each: one flat array with a ring of WALL cells around.

Cells are addressed by flat *keys* into the walled grid, so a neighbour is a key plus a fixed
offset and never needs a bounds check. A robot holds the cell it is in and every cell it has
reserved ahead; seeds hold theirs for good. A cell whose robot is leaving it may also have one
robot *queued* for it, which takes it over the moment it is left. This is the one record of
who is where.
"""

from __future__ import annotations

import numpy as np

FREE = -1
SEED = -2
WALL = -3
"""Holder codes besides robot indices (WALL: the ring of cells around the arena)."""


class Lattice:
    """Holders of every cell of a ``(width, height)`` arena, and which group owns each target."""

    def __init__(self, size: tuple[int, int]) -> None:
        width, height = size
        self.size = size
        self.stride = height + 2
        self.offsets = np.array([0, self.stride, -self.stride, 1, -1])
        """Key offset per direction index (see `swarmshape.core.motion.STEPS`)."""
        self.holder = np.full((width + 2) * (height + 2), WALL, dtype=np.int64)
        self.grid[...] = FREE
        self.owner = np.full(len(self.holder), -1, dtype=np.int32)  # groups: a few at most
        """Per key: the group whose target is there, or -1."""
        self.queued = np.full(len(self.holder), FREE, dtype=np.int64)
        """Per key: the robot that takes the cell over when its holder has left it, or FREE."""

    @property
    def grid(self) -> np.ndarray:
        """Holders as a ``[x, y]`` grid of the arena (a view: writing to it writes the lattice)."""
        width, height = self.size
        return self.holder.reshape(width + 2, height + 2)[1:-1, 1:-1]

    def key(self, cells: np.ndarray) -> np.ndarray:
        """Flat keys of ``(k, 2)`` cells."""
        return (cells[:, 0] + 1) * self.stride + cells[:, 1] + 1

    def mark_targets(self, targets: np.ndarray, groups: np.ndarray) -> None:
        """Record which group owns each target cell (again after the shape changed)."""
        self.owner[:] = -1
        self.owner[self.key(targets)] = groups

    def allows(self, keys: np.ndarray, groups: np.ndarray) -> np.ndarray:
        """Cells that are not another group's target (a group's shape is its own)."""
        owner = self.owner[keys]
        return (owner < 0) | (owner == groups)

    def enterable(self, keys: np.ndarray, groups: np.ndarray) -> np.ndarray:
        """Free cells that are not another group's target."""
        return (self.holder[keys] == FREE) & self.allows(keys, groups)

    def leave(self, keys: np.ndarray) -> np.ndarray:
        """The holders have left these cells: each goes to the robot queued for it, if any.
        Return those robots."""
        takers = self.queued[keys]
        self.holder[keys] = takers
        self.queued[keys] = FREE
        return takers[takers >= 0]

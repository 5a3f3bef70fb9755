"""Draw a `Swarm` onto any pygame Surface: the only module that knows about pixels.

The world is scaled to whole pixels per cell and centred in the given area. Grey cells are the
targets, green squares the seeds; agents take their group's colour, brightest while moving,
slightly darker once settled, pale while waiting or wandering.
"""

from __future__ import annotations

from itertools import repeat

import numpy as np
import pygame

from swarmshape.swarm import State, Swarm
from swarmshape.world import World

FLOOR = (250, 250, 247)
OUTSIDE = (222, 222, 216)
TARGET = (196, 196, 196)
SEED_GREEN = (34, 160, 60)

SHADES = {
    State.MOVING: lambda rgb: rgb,
    State.SETTLED: lambda rgb: tuple(int(c * 0.62) for c in rgb),
    State.WAITING: lambda rgb: tuple(int(c + (255 - c) * 0.55) for c in rgb),
    State.WANDERING: lambda rgb: tuple(int(c + (255 - c) * 0.35) for c in rgb),
}


class Renderer:
    """Draws one world; caches its static background for the current pixel scale."""

    def __init__(self, world: World) -> None:
        self.world = world
        self._background: pygame.Surface | None = None
        self._squares: dict[tuple[int, int], pygame.Surface] = {}

    def fit(self, area: pygame.Rect) -> tuple[int, tuple[int, int]]:
        """Whole pixels per cell and the pixel position of the world's top-left corner."""
        width, height = self.world.size
        cell = max(1, min(area.width // width, area.height // height))
        origin = (
            area.x + (area.width - cell * width) // 2,
            area.y + (area.height - cell * height) // 2,
        )
        return cell, origin

    def cell_rect(self, cell_xy: tuple[int, int], area: pygame.Rect) -> pygame.Rect:
        """The pixel rectangle of one world cell."""
        size, (ox, oy) = self.fit(area)
        return pygame.Rect(ox + cell_xy[0] * size, oy + cell_xy[1] * size, size, size)

    def draw(self, surface: pygame.Surface, swarm: Swarm, area: pygame.Rect | None = None) -> None:
        area = area or surface.get_rect()
        cell, origin = self.fit(area)
        surface.fill(OUTSIDE, area)
        surface.blit(self._background_at(cell), origin)
        gap = 1 if cell >= 4 else 0
        corner = np.floor((swarm.positions() - 0.5) * cell + np.array(origin) + gap).astype(int)
        for group, placed in enumerate(self.world.groups):
            for state, shade in SHADES.items():
                chosen = (swarm.group == group) & (swarm.state == state)
                if chosen.any():
                    square = self._square(cell - 2 * gap, shade(placed.colour))
                    surface.fblits(zip(repeat(square), map(tuple, corner[chosen].tolist())))

    def _background_at(self, cell: int) -> pygame.Surface:
        width, height = self.world.size
        if self._background is not None and self._background.get_width() == cell * width:
            return self._background
        background = pygame.Surface((cell * width, cell * height))
        background.fill(FLOOR)
        gap = 1 if cell >= 4 else 0
        for cells, colour in ((self.world.targets, TARGET), (self.world.seeds, SEED_GREEN)):
            for x, y in cells.tolist():
                background.fill(
                    colour, (x * cell + gap, y * cell + gap, cell - 2 * gap, cell - 2 * gap)
                )
        self._background = background
        return background

    def _square(self, side: int, colour: tuple[int, int, int]) -> pygame.Surface:
        key = (side, *colour)
        if key not in self._squares:
            square = pygame.Surface((max(1, side), max(1, side)))
            square.fill(colour)
            self._squares[key] = square
        return self._squares[key]

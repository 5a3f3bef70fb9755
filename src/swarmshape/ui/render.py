"""Draw a `Swarm` onto any pygame Surface: the only module that knows about pixels.

The world is scaled to whole pixels per cell and centred in the given area. Grey cells are the
targets, green squares the seeds; agents take their group's colour, brightest while moving,
slightly darker once settled, pale while waiting or wandering; stalled robots are charcoal, and
where a fault removed robots a red cross shows for `LOST_MARK_STEPS` steps.
"""

from __future__ import annotations

from itertools import pairwise, repeat

import numpy as np
import pygame

from swarmshape.core.swarm import Swarm
from swarmshape.core.world import World

FLOOR = (250, 250, 247)
OUTSIDE = (222, 222, 216)
TARGET = (196, 196, 196)
SEED_GREEN = (34, 160, 60)
LABEL_BACK = (38, 40, 46)
LABEL_TEXT = (235, 235, 235)
LOST_RED = (214, 40, 40)
STALLED_GREY = (64, 64, 70)
LOST_MARK_STEPS = 60
"""Steps for which a removed robot's last cell is marked."""
LABEL_SHARE = 1 / 22
"""A frame's text line is this share of its height (at least 14 pixels)."""

SHADES = (  # indexed by State
    lambda rgb: tuple(int(c + (255 - c) * 0.55) for c in rgb),  # waiting: pale
    lambda rgb: rgb,  # moving: the group's colour
    lambda rgb: tuple(int(c * 0.62) for c in rgb),  # settled: darker
    lambda rgb: tuple(int(c + (255 - c) * 0.35) for c in rgb),  # wandering: light
    lambda rgb: STALLED_GREY,  # stalled: charcoal, whatever the group
    lambda rgb: rgb,  # lost: never drawn
)


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

    def draw(
        self, surface: pygame.Surface, swarm: Swarm | None, area: pygame.Rect | None = None
    ) -> None:
        """Draw the world, and the swarm if there is one, into `area` (default: all of
        `surface`), scaled to fit."""
        area = area or surface.get_rect()
        cell, origin = self.fit(area)
        background = self._background_at(cell)
        world_rect = surface.blit(background, origin)
        for margin in _margins(area, world_rect):
            surface.fill(OUTSIDE, margin)
        if swarm is None:
            return
        gap = 1 if cell >= 4 else 0
        here = swarm.present
        corner = np.floor((swarm.positions() - 0.5) * cell + np.array(origin) + gap).astype(int)
        self._lost_marks(surface, swarm, cell, origin)
        corner = corner[here]
        kind = (swarm.group * len(SHADES) + swarm.state)[here]
        order = np.argsort(kind, kind="stable")
        bounds = np.searchsorted(kind[order], np.arange(len(self.world.groups) * len(SHADES) + 1))
        corners = corner[order].tolist()
        for index, (start, stop) in enumerate(pairwise(bounds)):
            if start < stop:  # one blit call per colour draws all its squares
                square = self._square(cell - 2 * gap, index)
                surface.fblits(zip(repeat(square), corners[start:stop]))

    def _lost_marks(
        self, surface: pygame.Surface, swarm: Swarm, cell: int, origin: tuple[int, int]
    ) -> None:
        """A red cross on the last cell of each robot removed in the last few steps."""
        lost_at = swarm.faults.lost_at
        recent = np.flatnonzero((lost_at >= 0) & (lost_at >= swarm.step_count - LOST_MARK_STEPS))
        width = max(1, cell // 6)
        for x, y in (swarm.cell[recent] * cell + np.array(origin)).tolist():
            inset = max(1, cell // 5)
            low, high = inset, cell - 1 - inset
            pygame.draw.line(surface, LOST_RED, (x + low, y + low), (x + high, y + high), width)
            pygame.draw.line(surface, LOST_RED, (x + low, y + high), (x + high, y + low), width)

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

    def _square(self, side: int, index: int) -> pygame.Surface:
        """A filled square for group ``index // len(SHADES)`` in state ``index % len(SHADES)``,
        made once."""
        key = (side, index)
        if key not in self._squares:
            group, state = divmod(index, len(SHADES))
            square = pygame.Surface((max(1, side), max(1, side)))
            square.fill(SHADES[state](self.world.groups[group].colour))
            self._squares[key] = square
        return self._squares[key]


def frame(
    swarm: Swarm,
    size: tuple[int, int] = (640, 400),
    renderer: Renderer | None = None,
    label: str | None = None,
) -> np.ndarray:
    """The swarm drawn offscreen as an RGB array ``(height, width, 3)``, no window needed;
    with a `label`, a line of text above the arena (recordings say their step this way)."""
    surface = pygame.Surface(size)
    area = surface.get_rect()
    if label is not None:
        font = _font(max(14, round(size[1] * LABEL_SHARE)))
        strip = pygame.Rect(0, 0, size[0], font.get_linesize() + 2)
        surface.fill(LABEL_BACK, strip)
        surface.blit(font.render(label, True, LABEL_TEXT), (4, 1))
        area = pygame.Rect(0, strip.bottom, size[0], max(1, size[1] - strip.bottom))
    (renderer or Renderer(swarm.world)).draw(surface, swarm, area)
    return np.ascontiguousarray(pygame.surfarray.array3d(surface).transpose(1, 0, 2))


def _font(height: int) -> pygame.font.Font:
    """pygame's own font at a pixel height (no display needed). Made afresh each time, a
    quarter of a millisecond: a kept one dies with any `pygame.quit`."""
    pygame.font.init()
    return pygame.font.Font(None, height)


def _margins(area: pygame.Rect, inner: pygame.Rect) -> list[pygame.Rect]:
    """The parts of `area` around `inner`: top, bottom, left, right."""
    return [
        pygame.Rect(area.left, area.top, area.width, inner.top - area.top),
        pygame.Rect(area.left, inner.bottom, area.width, area.bottom - inner.bottom),
        pygame.Rect(area.left, inner.top, inner.left - area.left, inner.height),
        pygame.Rect(inner.right, inner.top, area.right - inner.right, inner.height),
    ]

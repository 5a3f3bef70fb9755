"""Draw a `Swarm` onto any pygame Surface: the only module that knows about pixels.

The world is scaled to whole pixels per cell and centred in the given area. Grey cells are the
targets, green squares the seeds; agents take their group's colour, brightest while moving,
slightly darker once settled, pale while waiting, paler with a border of the full colour while
wandering (a spare robot with nothing to do); stalled robots are charcoal, and
where a fault removed robots a red cross shows for `LOST_MARK_STEPS` steps.

A driver that names its robots' states (`Driver.shown`: a local program's ``memory.state``) has
them coloured by state instead, from `PALETTE`; `legend` says what every colour on the arena
means, for any plug-in. Overlays, each optional, go on top: ``"values"`` prints the values the
driver shows on each robot, ``"links"`` draws a line for every message heard in the last step,
``"error"`` a red line from each localised robot to where it believes it is.
"""

from __future__ import annotations

from collections.abc import Collection
from itertools import pairwise, repeat
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pygame

from swarmshape.core.states import STALLED, WANDERING
from swarmshape.core.swarm import Shown, Swarm
from swarmshape.core.world import World

Colour = tuple[int, int, int]

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
LABEL_SHARE = 1 / 30
"""A recorded frame's text is this share of its height (at least 11 pixels)."""
FONT_FILE = Path(__file__).with_name("fonts") / "DejaVuSans.ttf"
"""DejaVu Sans, shipped (see fonts/README.md): pygame's own font spaces letters apart at the
sizes the window and recordings use ("set tled")."""

PALETTE = (  # Okabe and Ito's colour-blind-safe set first; no green, which marks seeds
    (0, 114, 178),  # blue
    (230, 159, 0),  # orange
    (204, 121, 167),  # reddish purple
    (86, 180, 233),  # sky blue
    (213, 94, 0),  # vermilion
    (240, 228, 66),  # yellow
    (140, 86, 75),  # brown
    (127, 127, 127),  # grey
    (148, 103, 189),  # violet
    (23, 190, 207),  # cyan
)
"""Colours of a program's states, in the order of `Program.states` (wrapping after ten)."""
OVERLAYS = ("values", "links", "error")
"""What `Renderer.draw` can draw over the robots, each on request."""
LINK_BLUE = (40, 90, 200, 110)
ERROR_RED = (220, 30, 30)
TEXT_DARK = (20, 20, 24)
TEXT_LIGHT = (250, 250, 250)
VALUE_MIN_CELL = 12
"""Pixels per cell below which numbers on robots are too small to read and are not drawn."""
UNKNOWN = 999
"""`Program.shown` values from this up (and negative ones) mean unknown: left blank."""

SHADES = (  # indexed by State
    lambda rgb: tuple(int(c + (255 - c) * 0.55) for c in rgb),  # waiting: pale
    lambda rgb: rgb,  # moving: the group's colour
    lambda rgb: tuple(int(c * 0.62) for c in rgb),  # settled: darker
    lambda rgb: tuple(int(c + (255 - c) * 0.35) for c in rgb),  # wandering: light (`BORDERED`)
    lambda rgb: STALLED_GREY,  # stalled: charcoal, whatever the group
    lambda rgb: rgb,  # lost: never drawn
)
SHADE_NAMES = ("waiting", "moving", "settled", "wandering")
"""What the first four `SHADES` show (stalled robots have one colour for every group)."""
BORDERED = WANDERING
"""The state drawn with a border of its group's full colour round its shade: its pale shade
alone was hard to tell from waiting's. Below `BORDER_MIN_SIDE` pixels a square has no border,
and its shade alone still tells it from a moving robot."""
BORDER_MIN_SIDE = 4


class Key(NamedTuple):
    """One line of the legend: a name and its swatches (one per group where groups differ),
    drawn as squares (with `borders`, one per swatch, if any: `BORDERED`), or as the red cross
    that marks a removed robot."""

    name: str
    colours: tuple[tuple[int, int, int], ...]
    cross: bool = False
    borders: tuple[tuple[int, int, int], ...] = ()


class Renderer:
    """Draws one world; caches its static background for the current pixel scale."""

    def __init__(self, world: World) -> None:
        self.world = world
        self._background: pygame.Surface | None = None
        self._squares: dict[tuple[int, Colour, Colour | None], pygame.Surface] = {}
        self._texts: dict[tuple[int, int, bool], pygame.Surface] = {}

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
        self,
        surface: pygame.Surface,
        swarm: Swarm | None,
        area: pygame.Rect | None = None,
        overlays: Collection[str] = (),
    ) -> None:
        """Draw the world, and the swarm if there is one, into `area` (default: all of
        `surface`), scaled to fit, with the named `OVERLAYS` on top (a local program's only)."""
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
        shown = swarm.driver.shown()  # asked once a frame: a driver may work it out each time
        kind, colours, borders = _colours(swarm, shown)
        kind = kind[here]
        order = np.argsort(kind, kind="stable")
        bounds = np.searchsorted(kind[order], np.arange(len(colours) + 1))
        corners = corner[order].tolist()
        looks = zip(colours, borders, pairwise(bounds), strict=True)
        for colour, border, (start, stop) in looks:
            if start < stop:  # one blit call per colour draws all its squares
                square = self._square(cell - 2 * gap, colour, border)
                surface.fblits(zip(repeat(square), corners[start:stop]))
        if shown is None or not overlays:
            return
        if "links" in overlays and shown.links is not None:
            self._links(surface, swarm, shown.links, cell, origin, world_rect)
        if "error" in overlays and shown.believes is not None:
            self._errors(surface, swarm, shown.believes, cell, origin)
        if "values" in overlays and shown.values is not None and cell >= VALUE_MIN_CELL:
            self._values(surface, swarm, shown.values, cell, origin, colours, kind)

    def _links(
        self,
        surface: pygame.Surface,
        swarm: Swarm,
        links: tuple[np.ndarray, np.ndarray],
        cell: int,
        origin: tuple[int, int],
        world_rect: pygame.Rect,
    ) -> None:
        """A thin line per pair of robots (or robot and seed) that heard each other in the last
        step, drawn once per pair on one translucent layer."""
        if not len(links[0]):
            return
        owner, other = links
        n = len(swarm.cell)
        centres = np.concatenate([swarm.positions(), swarm.world.seeds + 0.5])
        alive = np.concatenate([swarm.present, np.ones(len(swarm.world.seeds), dtype=bool)])
        keep = alive[owner] & alive[other]
        low, high = np.minimum(owner, other)[keep], np.maximum(owner, other)[keep]
        pairs = np.unique(low * (n + len(swarm.world.seeds)) + high)
        low, high = np.divmod(pairs, n + len(swarm.world.seeds))
        ends = np.floor(centres * cell).astype(int)  # relative to the world's corner
        layer = pygame.Surface(world_rect.size, pygame.SRCALPHA)
        line, width = pygame.draw.line, 1 if cell < 24 else 2
        for a, b in zip(ends[low].tolist(), ends[high].tolist(), strict=True):
            line(layer, LINK_BLUE, a, b, width)
        surface.blit(layer, origin)

    def _errors(
        self,
        surface: pygame.Surface,
        swarm: Swarm,
        believes: tuple[np.ndarray, np.ndarray],
        cell: int,
        origin: tuple[int, int],
    ) -> None:
        """A red line from each localised robot's centre to the centre of the cell it believes
        it is on, ending in a dot there; none where that is its cell, as the metrics count it
        (a robot under way still counts the cell it left)."""
        robots = np.flatnonzero(believes[0])
        believed = believes[1][robots]
        off = (believed != swarm.cell[robots]).any(axis=1)
        truth, believed = swarm.positions()[robots], believed + 0.5
        at = np.array(origin)
        starts = np.floor(truth[off] * cell + at).astype(int).tolist()
        ends = np.floor(believed[off] * cell + at).astype(int).tolist()
        width, dot = max(1, cell // 8), max(2, cell // 6)
        for a, b in zip(starts, ends, strict=True):
            pygame.draw.line(surface, ERROR_RED, a, b, width)
            pygame.draw.circle(surface, ERROR_RED, b, dot)

    def _values(
        self,
        surface: pygame.Surface,
        swarm: Swarm,
        values: np.ndarray,
        cell: int,
        origin: tuple[int, int],
        colours: list[tuple[int, int, int]],
        kind: np.ndarray,
    ) -> None:
        """The driver's shown value on each present robot, dark or light to suit its colour."""
        here = np.flatnonzero(swarm.present)
        values = values[here]
        known = (values >= 0) & (values < UNKNOWN)
        centre = np.floor(swarm.positions()[here] * cell + np.array(origin)).astype(int)
        light = np.array([sum(c) < 330 for c in colours])[kind]
        font = font_of(max(6, round(cell * 0.55)))
        blits = []
        for value, (x, y), on_dark in zip(
            values[known].tolist(), centre[known].tolist(), light[known].tolist(), strict=True
        ):
            text = self._text(font, cell, int(value), on_dark)
            blits.append((text, (x - text.get_width() // 2, y - text.get_height() // 2)))
        surface.fblits(blits)

    def _text(self, font: pygame.font.Font, cell: int, value: int, light: bool) -> pygame.Surface:
        """A number rendered once per cell size and colour, shrunk to fit inside a cell."""
        key = (cell, value, light)
        if key not in self._texts:
            text = font.render(str(value), True, TEXT_LIGHT if light else TEXT_DARK)
            room = cell - 2
            if text.get_width() > room:
                scale = room / text.get_width()
                text = pygame.transform.smoothscale(
                    text, (room, max(1, round(text.get_height() * scale)))
                )
            self._texts[key] = text
        return self._texts[key]

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

    def _square(self, side: int, colour: Colour, border: Colour | None) -> pygame.Surface:
        """A square of one colour, with a `border` if given (see `square_of`), made once."""
        key = (side, colour, border)
        if key not in self._squares:
            self._squares[key] = square_of(max(1, side), colour, border)
        return self._squares[key]


def square_of(side: int, colour: Colour, border: Colour | None = None) -> pygame.Surface:
    """A `side`-pixel square of `colour`, with a `border` a quarter of its side wide if given
    (none below `BORDER_MIN_SIDE`)."""
    square = pygame.Surface((side, side))
    square.fill(colour)
    if border is not None and side >= BORDER_MIN_SIDE:
        pygame.draw.rect(square, border, square.get_rect(), side // 4)
    return square


def shown_of(swarm: Swarm | None) -> Shown | None:
    """What the driver of `swarm` shows beyond where robots are (None: nothing, or no swarm)."""
    return None if swarm is None else swarm.driver.shown()


def _named_states(shown: Shown | None) -> list[tuple[str, tuple[int, int, int]]]:
    """The driver's state names and their colours, when robots are coloured by state."""
    if shown is None or shown.state is None:
        return []
    return [(name, PALETTE[i % len(PALETTE)]) for i, name in enumerate(shown.states)]


def legend(swarm: Swarm) -> list[Key]:
    """What every colour on the arena means: a local program's named states, or else what
    robots are doing, in each group's shade (central strategies, and programs that name no
    states); then stalled and removed robots, seeds and empty target cells."""
    named = _named_states(shown_of(swarm))
    if named:
        keys = [Key(name, (colour,)) for name, colour in named]
    else:
        groups = [group.colour for group in swarm.world.groups]
        keys = []
        for state, (name, shade) in enumerate(zip(SHADE_NAMES, SHADES, strict=False)):
            looks = dict.fromkeys((shade(colour), colour) for colour in groups)  # one per look
            borders = tuple(border for _, border in looks) if state == BORDERED else ()
            keys.append(Key(name, tuple(colour for colour, _ in looks), borders=borders))
    return [
        *keys,
        Key("stalled", (STALLED_GREY,)),
        Key("removed", (LOST_RED,), cross=True),
        Key("seed", (SEED_GREEN,)),
        Key("empty cell", (TARGET,)),
    ]


def _colours(
    swarm: Swarm, shown: Shown | None
) -> tuple[np.ndarray, list[Colour], list[Colour | None]]:
    """Each robot's colour index, the colours, and a border for each (None: none): by the
    states the driver `shown` names (a local program's ``memory.state``), else its group's
    colour shaded by what it is doing, with a border of that colour for `BORDERED` (stalled
    robots are charcoal either way)."""
    named = _named_states(shown)
    if shown is not None and shown.state is not None:
        colours = [colour for _, colour in named] + [STALLED_GREY]
        kind = shown.state % len(named)
        return np.where(swarm.state == STALLED, len(named), kind), colours, [None] * len(colours)
    groups = [g.colour for g in swarm.world.groups]
    colours = [shade(colour) for colour in groups for shade in SHADES]
    borders = [
        colour if state == BORDERED else None for colour in groups for state in range(len(SHADES))
    ]
    return swarm.group * len(SHADES) + swarm.state, colours, borders


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
        font = font_of(max(11, round(size[1] * LABEL_SHARE)))
        strip = pygame.Rect(0, 0, size[0], font.get_linesize() + 2)
        surface.fill(LABEL_BACK, strip)
        surface.blit(font.render(label, True, LABEL_TEXT), (4, 1))
        area = pygame.Rect(0, strip.bottom, size[0], max(1, size[1] - strip.bottom))
    (renderer or Renderer(swarm.world)).draw(surface, swarm, area)
    return np.ascontiguousarray(pygame.surfarray.array3d(surface).transpose(1, 0, 2))


def font_of(size: int) -> pygame.font.Font:
    """The shipped font at `size` pixels (a line is about 1.2 times that; no display needed).
    Made afresh each time, a quarter of a millisecond: a kept one dies with any `pygame.quit`."""
    pygame.font.init()
    return pygame.font.Font(FONT_FILE, size)


def _margins(area: pygame.Rect, inner: pygame.Rect) -> list[pygame.Rect]:
    """The parts of `area` around `inner`: top, bottom, left, right."""
    return [
        pygame.Rect(area.left, area.top, area.width, inner.top - area.top),
        pygame.Rect(area.left, inner.bottom, area.width, area.bottom - inner.bottom),
        pygame.Rect(area.left, inner.top, inner.left - area.left, inner.height),
        pygame.Rect(inner.right, inner.top, area.right - inner.right, inner.height),
    ]

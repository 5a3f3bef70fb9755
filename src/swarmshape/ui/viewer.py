"""The window: main loop, keys, heads-up display, screenshots, and the editor on top.

The window drives a `runs.Runner`, the loop every run goes through: its observers (recorders,
traces) see each step, it stops at its `max_steps`, and it says when the run is `finished`.
Each call of `Viewer.tick` handles pending events, advances the run by the current speed, and
draws one frame, so tests can post events and drive it frame by frame under
``SDL_VIDEODRIVER=dummy``. While nothing can change without the user (paused, finished with
every robot at rest, out of steps, no swarm yet) a tick waits for an event instead, and draws
only if one came, so an idle window costs no CPU; the HUD says why it is idle. `e` switches
into the editor while the swarm keeps running; Enter (or `e` again) hands the painted shape to
the swarm, or starts one if none runs yet. `x` toggles the fault tool: a click removes the
robot under the cursor, a drag removes every robot in the rectangle. Under a local program,
robots may take the colours of its states, and `g`, `l`, `o` toggle the overlays: its gradient
values, its communication links, and its localisation error.

The HUD is a bar at the top (the status; then a notice, or what runs) and one at the bottom
(the legend of every colour on the arena, then the keys), each wrapped to the window's width.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from itertools import count
from math import ceil
from pathlib import Path

import numpy as np
import pygame

from swarmshape.core.states import MOVING, SETTLED, WANDERING
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.errors import InputError
from swarmshape.io.files import OutputError, atomic_write
from swarmshape.runs import Observer, Runner
from swarmshape.ui.editor import HELP_LINES, Canvas, Editor
from swarmshape.ui.render import (
    FLOOR,
    VALUE_MIN_CELL,
    Key,
    Renderer,
    font_of,
    legend,
    shown_of,
    square_of,
)

FAULT_EVENTS = (pygame.MOUSEBUTTONDOWN, pygame.MOUSEMOTION, pygame.MOUSEBUTTONUP)

SPEEDS = (0.125, 0.25, 0.5, 1, 2, 4, 8, 16, 32, 64, 128, 256)
"""Simulation steps per frame that `+` and `-` move between."""

SPARE_WHEN_PAINTED = 0.25
"""A swarm started from a painting gets this share of spare robots, to recruit on re-edits."""

IDLE_WAIT_MS = 250
"""How long an idle tick waits for an event; any event ends the wait at once."""

HUD_BACK = (38, 40, 46)
HUD_TEXT = (235, 235, 235)
HUD_DIM = (150, 155, 165)
HUD_NOTICE = (255, 206, 84)
HUD_PAD = 6
"""Pixels around the bars' text."""
GAP = "   "
"""Between the parts of a HUD line; lines wrap here first, then between words."""
FONT_SHARE = 1 / 50
"""The HUD's text is this share of the window's height, within `FONT_SIZES`."""
FONT_SIZES = (11, 20)
HELP = (
    "Space pause", ". step", "+ - speed", "r restart", "e edit", "x fault tool",
    "g l o overlays", "F12 screenshot", "q quit",
)  # fmt: skip
EDIT_HELP = ("h help", "Enter: hand the shape to the swarm", "Ctrl+S save", "q quit")
OVERLAY_KEYS = {pygame.K_g: "values", pygame.K_l: "links", pygame.K_o: "error"}
"""Keys that toggle `render.OVERLAYS`: a local program's gradient values, communication links
and localisation error."""
FAULT_HELP = "fault tool: click removes a robot, drag removes all in a rectangle   x: done"
DRAG_RED = (214, 40, 40)


class Viewer:
    """A resizable window on one world; `make_swarm` builds (and on `r` rebuilds) its run.

    With ``start=False`` the window opens in the editor and no swarm runs until the user
    hands over a shape. Like a headless run, it stops stepping once `max_steps` steps have run
    in total (None: no limit); `swarm` is the run as it ended when the window closes.
    """

    def __init__(
        self,
        make_swarm: Callable[[World], Swarm],
        world: World,
        *,
        title: str,
        start: bool = True,
        shape_file: Path | None = None,
        size: tuple[int, int] = (1280, 800),
        speed: float = 8,
        fps: int = 60,
        screenshots: Path = Path(),
        observers: Sequence[Observer] = (),
        max_steps: int | None = None,
    ) -> None:
        pygame.display.init()  # not pygame.init(): no sound, so no audio device needed
        pygame.display.set_caption(f"swarmshape - {title}")
        self.screen = pygame.display.set_mode(size, pygame.RESIZABLE)
        self.font = font_of(self._font_size())
        self.clock = pygame.time.Clock()
        self.title = title
        self.make_swarm = make_swarm
        self.observers = tuple(observers)
        """Recorders and traces, handed to each run's `Runner`."""
        self.max_steps = max_steps
        """Passed to the `Runner` (None: its default)."""
        self.world = world
        self.runner: Runner | None = None
        """The run on show, None until the editor hands over a first shape."""
        if start:
            self.start_run(world)
        self.renderer = Renderer(world)
        self.speed_index = min(range(len(SPEEDS)), key=lambda i: abs(SPEEDS[i] - speed))
        self.fps = fps
        self.screenshots = screenshots
        self.paused = False
        self.running = True
        self.notice = ""
        self._budget = 0.0
        self._redraw = True
        self.editor: Editor | None = None
        self.editing = False
        self._group = 0
        """The group being edited."""
        self._backdrop: tuple | None = None
        """What the editor's arena was drawn for, and its renderer."""
        self._shape_file = shape_file
        self.fault_tool = False
        """While on, clicks and drags remove robots."""
        self._drag_from: tuple[int, int] | None = None
        """The cell a fault-tool drag started on."""
        self._drag_to: tuple[int, int] | None = None
        self.overlays: set[str] = set()
        """What `render.Renderer.draw` draws over a local program's robots."""
        self._area: pygame.Rect | None = None
        """Where the arena was last drawn: clicks land on what the user sees."""
        if not start:
            self.start_editing()

    @property
    def swarm(self) -> Swarm | None:
        return None if self.runner is None else self.runner.swarm

    def start_run(self, world: World) -> None:
        """A new run on `world` (the first, a restart, or the editor's first shape)."""
        self.runner = Runner(self.make_swarm(world), self.observers, self.max_steps)

    @property
    def speed(self) -> float:
        return SPEEDS[self.speed_index]

    def run(self) -> None:
        """Until the user quits; then the run's observers write their files, as at the end of
        a headless run (or drop what they had half-written if the window failed)."""
        try:
            while self.tick():
                pass
        except BaseException:
            if self.runner is not None:
                self.runner.discard()
            pygame.quit()
            raise
        if self.runner is not None:
            self.runner.close()
        pygame.quit()

    @property
    def out_of_steps(self) -> bool:
        return self.runner is not None and self.runner.out_of_steps

    @property
    def idle(self) -> bool:
        """Nothing changes unless the user acts (`why_idle` says what holds it)."""
        return self.why_idle() is not None

    def why_idle(self) -> str | None:
        """Why the window waits for the user instead of stepping: no swarm yet, paused, out of
        steps, or the run finished (formed, stranded, or a local program gone quiet, with no
        fault still to come) with every robot at rest and none wandering; None while it steps."""
        runner = self.runner
        if runner is None:
            return "no swarm yet"
        if self.paused:
            return "PAUSED, Space goes on"
        if runner.out_of_steps:
            return "stopped at max steps"
        swarm = runner.swarm
        moving = np.isin(swarm.state, (MOVING, WANDERING)).any() or swarm.ahead.any()
        if not runner.finished or moving:
            return None
        if swarm.complete:
            open_cells = int((~swarm.filled & ~swarm.dead).sum())
            if open_cells:  # faults left fewer robots than cells, and the shape kept its size
                cells = "cell" if open_cells == 1 else "cells"
                return f"formed as far as the robots go, {open_cells:,} {cells} open"
            return "formed, nothing moves"
        if swarm.stranded:
            return "stranded: no robot can reach the shape"
        return f"{swarm.plugin.name} has gone quiet, nothing moves"

    def tick(self) -> bool:
        """One frame: events, simulation, drawing. Returns False once the user quit.

        When idle it waits up to `IDLE_WAIT_MS` for an event and redraws only after one."""
        events = pygame.event.get()
        if not events and self.idle:
            first = pygame.event.wait(IDLE_WAIT_MS)
            events = [first, *pygame.event.get()] if first.type != pygame.NOEVENT else []
        for event in events:
            self.handle(event)
        if self.running and not self.idle:  # once the user quit, the run is as they saw it
            self._budget += self.speed
            while self._budget >= 1 and not self.idle:
                self.step()
                self._budget -= 1
            self._redraw = True
        if events or self._redraw:
            self.draw()
            pygame.display.flip()
            self._redraw = False
        self.clock.tick(self.fps)
        return self.running

    def handle(self, event: pygame.event.Event) -> None:
        if event.type == pygame.QUIT:
            self.quit()
        elif event.type == pygame.VIDEORESIZE:  # SDL has resized the window's surface
            self.screen = pygame.display.get_surface()  # set_mode would make a new window
            self.font = font_of(self._font_size())
        elif event.type == pygame.KEYDOWN and event.key == pygame.K_F12:
            try:
                self.notice = f"saved {self.screenshot()}"
            except OutputError as error:  # a screenshot is a side line: the run goes on
                self.notice = f"screenshot not saved: {error}"
        elif self.editing:
            outcome = self.editor.handle(event, self.cell_at)
            if outcome == "apply":
                self.finish_editing()
            elif outcome == "quit":
                self.quit()
            else:
                self._follow_editor()
        elif self.fault_tool and event.type in FAULT_EVENTS:
            self._fault_tool(event)
        elif event.type == pygame.KEYDOWN:
            self._key(event)

    def _fault_tool(self, event: pygame.event.Event) -> None:
        """A press starts a rectangle, a move stretches it, a release removes the robots in it
        (a click: the robot under the cursor)."""
        cell = self.cell_at(event.pos)
        if event.type == pygame.MOUSEBUTTONDOWN and event.button == 1:
            self._drag_from = self._drag_to = cell
        elif event.type == pygame.MOUSEMOTION and self._drag_from is not None:
            self._drag_to = cell or self._drag_to
        elif event.type == pygame.MOUSEBUTTONUP and event.button == 1:
            start, end = self._drag_from, cell or self._drag_to
            self._drag_from = self._drag_to = None
            if start is None or end is None or self.swarm is None:
                return
            self.remove_robots(start, end)

    def remove_robots(self, corner: tuple[int, int], other: tuple[int, int]) -> int:
        """Remove every robot whose square's centre lies in the rectangle of cells between two
        corners (one cell: the robot on it); say how many."""
        swarm = self.swarm
        low, high = np.minimum(corner, other), np.maximum(corner, other)
        under = swarm.cells_under()
        inside = (under >= low).all(axis=1) & (under <= high).all(axis=1) & swarm.present
        robots = np.flatnonzero(inside)
        if len(robots):
            swarm.fail(robots, "remove", label="window")
            self._follow_world()
        self.notice = f"removed {len(robots)} robot{'' if len(robots) == 1 else 's'}"
        return len(robots)

    def _key(self, event: pygame.event.Event) -> None:
        key = event.key
        if key in (pygame.K_ESCAPE, pygame.K_q):
            self.quit()
        elif key == pygame.K_SPACE:
            self.paused = not self.paused
        elif key == pygame.K_PERIOD and self.swarm is not None:
            self.paused = True
            if self.out_of_steps:
                self.notice = f"stopped at --max-steps {self.max_steps}"
            else:
                self.step()
        elif key in (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS):
            self.speed_index = min(self.speed_index + 1, len(SPEEDS) - 1)
        elif key in (pygame.K_MINUS, pygame.K_KP_MINUS):
            self.speed_index = max(self.speed_index - 1, 0)
        elif key == pygame.K_r and self.swarm is not None:
            self.start_run(self.world)
            self.notice = f"restarted with seed {self.swarm.seed}"
        elif key == pygame.K_e:
            self.start_editing()
        elif key == pygame.K_x and self.swarm is not None:
            self.fault_tool = not self.fault_tool
            self._drag_from = self._drag_to = None
            self.notice = FAULT_HELP if self.fault_tool else "fault tool off"
        elif key in OVERLAY_KEYS:
            self.toggle_overlay(OVERLAY_KEYS[key])

    def toggle_overlay(self, name: str) -> None:
        """Switch one overlay on or off and say so, or say why it would show nothing."""
        shown = shown_of(self.swarm)
        if shown is None:
            self.notice = "no local program: overlays show a local program's values and links"
            return
        if name in self.overlays:
            self.overlays.discard(name)
            self.notice = f"{name} overlay off"
            return
        self.overlays.add(name)
        self.notice = f"{name} overlay on"
        if name == "values" and shown.values is None:
            self.notice += f": {shown.plugin} shows no memory slot (Program.shown)"
        elif name == "values" and self.renderer.fit(self._world_area())[0] < VALUE_MIN_CELL:
            self.notice += ": cells too small to read, enlarge the window"
        elif name == "error" and shown.believes is None:
            self.notice += f": {shown.plugin} does not localise (Program.estimate)"

    def step(self) -> None:
        self.runner.step()
        self._follow_world()

    def _follow_world(self) -> None:
        """Draw the world the swarm has now (a fault may have re-formed it smaller)."""
        if self.swarm.world is not self.world and not self.editing:
            self.world = self.swarm.world
            self.renderer = Renderer(self.world)

    def quit(self) -> None:
        """Stop; a painting that was never saved is kept as NAME.autosave.png first."""
        self.running = False
        if self.editor is not None:
            kept = self.editor.autosave()
            if kept is not None:
                print(f"swarmshape: unsaved shape kept in {kept}", file=sys.stderr)
            elif self.editor.dirty and self.editor.shape() is not None:
                print(f"swarmshape: unsaved shape lost, {self.editor.message}", file=sys.stderr)

    # --- the editor ---------------------------------------------------------------------

    def start_editing(self, group: int = 0) -> None:
        """Paint over the arena; the swarm, if any, keeps running underneath."""
        placed = self.world.groups[group]
        others = [g for i, g in enumerate(self.world.groups) if i != group]
        fixed = np.concatenate([np.zeros((0, 2), np.int64)] + [g.targets for g in others])
        fixed = np.concatenate([fixed] + [g.seeds for g in others])
        self._group = group
        if self.editor is None:
            self.editor = Editor(
                Canvas(self.world.size, placed.targets),
                placed.pose,
                path=self._shape_file,
                agents=None if self.swarm is None else placed.agents,
                resizable=self.swarm is None,
                fixed=fixed,
            )
        self.editing = True
        self._follow_editor()

    def _follow_editor(self) -> None:
        """Draw the arena as the editor has it now: its size, its seeds, no stale shape
        (rebuilt only when one of those changed, not on every mouse move)."""
        editor = self.editor
        key = (editor.canvas.size, editor.pose, len(editor.fixed))
        if self._backdrop != (key, self.renderer):
            self.renderer = Renderer(editor.backdrop(self.world, self._group))
            self._backdrop = (key, self.renderer)

    def finish_editing(self, group: int = 0) -> None:
        """Hand the painted shape over: re-form the running swarm, or start one."""
        editor = self.editor
        shape = editor.shape()
        if shape is None:
            editor.message = "paint some cells first"
            return
        try:
            if self.swarm is None:
                placed = self.world.groups[group]
                agents = shape.count + ceil(SPARE_WHEN_PAINTED * shape.count)
                spec = GroupSpec(placed.name, shape, placed.colour, agents, editor.pose)
                self.world = build_world([spec], editor.canvas.size)
                self.start_run(self.world)
                editor.agents, editor.resizable = self.world.agents, False
            else:
                self.swarm.reshape(group, shape, editor.pose)
                self.world = self.swarm.world
        except InputError as error:
            editor.message = str(error)
            return
        self.renderer = Renderer(self.world)
        self.editing = False
        self.notice = f"new shape: {len(self.world.groups[group].targets)} cells"

    def cell_at(self, pixel: tuple[int, int]) -> tuple[int, int] | None:
        """The world cell under a pixel, or None outside the arena."""
        cell, (ox, oy) = self.renderer.fit(self._world_area())
        x, y = (pixel[0] - ox) // cell, (pixel[1] - oy) // cell
        width, height = self.renderer.world.size
        return (x, y) if 0 <= x < width and 0 <= y < height else None

    # --- drawing ------------------------------------------------------------------------

    def screenshot(self) -> Path:
        """Save the window as PNG (atomically) under a name no file has yet (nobody named
        it: it never replaces one), and return its path."""
        step = 0 if self.swarm is None else self.swarm.step_count
        stem = Path(self.title).stem.replace(" ", "-")
        names = (f"swarmshape-{stem}-{step}{'' if n == 1 else f'-{n}'}.png" for n in count(1))
        path = next(path for name in names if not (path := self.screenshots / name).exists())
        atomic_write(path, lambda tmp: pygame.image.save(self.screen, tmp))
        print(f"screenshot: {path}")
        return path

    def _font_size(self) -> int:
        low, high = FONT_SIZES
        return max(low, min(high, round(self.screen.get_height() * FONT_SHARE)))

    def _world_area(self) -> pygame.Rect:
        """Where the arena is: where it was last drawn, or between the bars as they are now."""
        return self._area or self._layout()[3]

    def _layout(self) -> tuple[list[tuple[str, tuple]], list[list[Key]], list[str], pygame.Rect]:
        """The top bar's lines with their colours, the legend's rows and the keys' lines of the
        bottom bar, and the arena between the bars. The legend is left out of a window so small
        that it would leave the arena less than half the height."""
        said = self._said()
        top = [(line, HUD_TEXT) for line in self._wrap(self.status())]
        second = HUD_NOTICE if said else HUD_DIM
        top += [(line, second) for line in self._wrap(said or self._about())]
        keys = self._key_rows(legend(self.swarm)) if self.swarm and not self.editing else []
        helps = self._wrap(GAP.join(EDIT_HELP if self.editing else HELP))
        line = self.font.get_linesize()
        width, height = self.screen.get_size()
        above = len(top) * line + 2 * HUD_PAD
        below = len(helps) * line + 2 * HUD_PAD
        if above + below + len(keys) * line > height / 2:
            keys = []
        below += len(keys) * line
        return top, keys, helps, pygame.Rect(0, above, width, max(1, height - above - below))

    def draw(self) -> None:
        top, keys, helps, area = self._layout()
        self._area = area
        self.renderer.draw(self.screen, self.swarm, area, self.overlays)
        if self._drag_from is not None and self._drag_to is not None:
            first = self.renderer.cell_rect(self._drag_from, area)
            pygame.draw.rect(
                self.screen, DRAG_RED, first.union(self.renderer.cell_rect(self._drag_to, area)), 2
            )
        if self.editing:
            self.editor.draw(self.screen, lambda cell: self.renderer.cell_rect(cell, area))
            if self.editor.show_help:
                panel = self._help_panel(area)
                self.screen.fill(HUD_BACK, panel)
                step = self.font.get_linesize() + 2
                for row, line in enumerate(HELP_LINES):
                    self._text(line, (panel.x + 10, panel.y + 5 + step * row), HUD_TEXT)
        width, height = self.screen.get_size()
        line = self.font.get_linesize()
        self.screen.fill(HUD_BACK, (0, 0, width, area.top))
        self.screen.fill(HUD_BACK, (0, area.bottom, width, height - area.bottom))
        for row, (text, colour) in enumerate(top):
            self._text(text, (HUD_PAD, HUD_PAD + row * line), colour)
        for row, row_keys in enumerate(keys):
            self._keys(row_keys, area.bottom + HUD_PAD + row * line)
        for row, text in enumerate(helps):
            self._text(text, (HUD_PAD, area.bottom + HUD_PAD + (len(keys) + row) * line), HUD_DIM)

    def _wrap(self, text: str) -> list[str]:
        """`text` in lines that fit the window's width, broken between its parts (`GAP`), or
        between words where one part alone is too wide; at least one line, if an empty one."""
        room = self.screen.get_width() - 2 * HUD_PAD

        def fits(line: str) -> bool:
            return self.font.size(line)[0] <= room

        lines = [""]
        for part in text.split(GAP):
            words = [part] if fits(part) else part.split(" ")
            for index, word in enumerate(words):
                joined = f"{lines[-1]}{' ' if index else GAP}{word}" if lines[-1] else word
                if fits(joined):
                    lines[-1] = joined
                else:
                    lines.append(word)
        return lines

    def _swatch(self) -> int:
        return max(6, round(0.7 * self.font.get_height()))

    def _key_width(self, key: Key) -> int:
        return len(key.colours) * (self._swatch() + 2) + 3 + self.font.size(key.name)[0]

    def _key_rows(self, keys: list[Key]) -> list[list[Key]]:
        """The legend's keys in rows that fit the window's width."""
        room, gap = self.screen.get_width() - 2 * HUD_PAD, self.font.size(GAP)[0]
        rows: list[list[Key]] = []
        used = room
        for key in keys:
            width = self._key_width(key)
            if used + gap + width > room:
                rows.append([])
                used = -gap
            rows[-1].append(key)
            used += gap + width
        return rows

    def _keys(self, keys: list[Key], y: int) -> None:
        """One row of the legend: each key's swatches (a square per colour, bordered as robots
        are, or a red cross on the floor for removed robots) and its name."""
        side, x = self._swatch(), HUD_PAD
        top = y + (self.font.get_linesize() - side) // 2
        for key in keys:
            for index, colour in enumerate(key.colours):
                square = pygame.Rect(x, top, side, side)
                if key.cross:
                    self.screen.fill(FLOOR, square)
                    inner = square.inflate(-side // 3, -side // 3)
                    pygame.draw.line(self.screen, colour, inner.topleft, inner.bottomright, 2)
                    pygame.draw.line(self.screen, colour, inner.bottomleft, inner.topright, 2)
                else:
                    border = key.borders[index] if key.borders else None
                    self.screen.blit(square_of(side, colour, border), square)
                x += side + 2
            self._text(key.name, (x + 3, y), HUD_TEXT)
            x += 3 + self.font.size(key.name)[0] + self.font.size(GAP)[0]

    def _help_panel(self, area: pygame.Rect) -> pygame.Rect:
        """The corner of `area` where the help covers the fewest seeds, then painted cells."""
        width = max(self.font.size(line)[0] for line in HELP_LINES) + 20
        panel = pygame.Rect(0, 0, width, (self.font.get_linesize() + 2) * len(HELP_LINES) + 10)
        inner = area.inflate(-16, -16)
        corners = [
            panel.move_to(bottomright=inner.bottomright),
            panel.move_to(topright=inner.topright),
            panel.move_to(bottomleft=inner.bottomleft),
            panel.move_to(topleft=inner.topleft),
        ]
        size, origin = self.renderer.fit(area)
        seeds = self.editor.seeds * size + np.array(origin)
        painted = self.editor.canvas.cells * size + np.array(origin)

        def covered(corner: pygame.Rect, cells: np.ndarray) -> int:
            low, high = np.array(corner.topleft), np.array(corner.bottomright)
            return int(((cells < high) & (cells + size > low)).all(axis=1).sum())

        return min(corners, key=lambda c: (covered(c, seeds), covered(c, painted)))

    def _text(self, text: str, where: tuple[int, int], colour: tuple[int, int, int]) -> None:
        self.screen.blit(self.font.render(text, True, colour), where)

    def _said(self) -> str:
        """What the window has to tell the user now: a notice, or the editor's question or
        message; empty if nothing."""
        if not self.editing:
            return self.notice
        return self.editor.prompt() or self.editor.message

    def _about(self) -> str:
        """What is on show, when there is nothing to tell."""
        if self.editing:
            under = "; the swarm runs on underneath" if self.swarm is not None else ""
            return f"left button paints, right button erases{under}"
        world = self.swarm.world
        return (
            f"{self.title}: {self.swarm.plugin.name}, {world.agents:,} robots for "
            f"{len(world.targets):,} cells"
        )

    def _second_line(self) -> str:
        return self._said() or self._about()

    def status(self) -> str:
        if self.editing:
            return self.editor.status()
        swarm = self.swarm
        settled = int((swarm.state == SETTLED).sum())
        parts = [
            f"step {swarm.step_count:,}/{self.runner.max_steps:,}",
            f"settled {settled:,}/{len(swarm.filled):,}",
            f"coverage {100 * swarm.filled.mean():.1f}%",
            self._pace(),
            self._rate(),
            f"seed {swarm.seed}",
        ]
        done = swarm.completed_at
        if None not in done:
            parts.append(f"formed at step {max(done):,}")
        missing = len(swarm.filled) - len(swarm.cell)
        if missing > 0:
            parts.append(f"{missing:,} robots short")
        if swarm.faults.lost:
            parts.append(f"lost {swarm.faults.lost:,}")
        if self.fault_tool:
            parts.append("FAULT TOOL")
        if self.overlays and shown_of(swarm) is not None:
            parts.append("showing " + " ".join(sorted(self.overlays)))
        return GAP.join(parts)

    def _pace(self) -> str:
        """Steps per frame, in words that read right for one step and for fractions."""
        speed = self.speed
        if speed >= 1:
            return f"{speed:g} step{'' if speed == 1 else 's'}/frame"
        return f"1 step/{1 / speed:g} frames"

    def _rate(self) -> str:
        """Frames per second while the run goes on; once the window waits, why it does."""
        why = self.why_idle()
        if why is not None:
            return f"idle: {why}"
        fps = self.clock.get_fps()
        return f"{fps:.0f} FPS" if fps >= 1 else "measuring FPS"

"""The window: main loop, keys, heads-up display, screenshots, and the editor on top.

The window drives a `runs.Runner`, the loop every run goes through: its observers (recorders,
traces) see each step, it stops at its `max_steps`, and it says when the run is `finished`.
Each call of `Viewer.tick` handles pending events, advances the run by the current speed, and
draws one frame, so tests can post events and drive it frame by frame under
``SDL_VIDEODRIVER=dummy``. While nothing can change without the user (paused, finished with
every robot at rest, out of steps, no swarm yet) a tick waits for an event instead, and draws
only if one came, so an idle window costs no CPU. `e` switches into the editor while the swarm keeps
running; Enter (or `e` again) hands the painted shape to the swarm, or starts one if none runs
yet. `x` toggles the fault tool: a click removes the robot under the cursor, a drag removes
every robot in the rectangle. Under a local program, robots take the colours of its states (a
legend in the corner names them) and `g`, `l`, `o` toggle the overlays: its gradient values,
its communication links, and its localisation error.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from math import ceil
from pathlib import Path

import numpy as np
import pygame

from swarmshape.core.states import MOVING, SETTLED, WANDERING
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write
from swarmshape.runs import Observer, Runner
from swarmshape.ui.editor import HELP_LINES, Canvas, Editor
from swarmshape.ui.render import VALUE_MIN_CELL, Renderer, legend, program_of

FAULT_EVENTS = (pygame.MOUSEBUTTONDOWN, pygame.MOUSEMOTION, pygame.MOUSEBUTTONUP)

SPEEDS = (0.125, 0.25, 0.5, 1, 2, 4, 8, 16, 32, 64, 128, 256)
"""Simulation steps per frame that `+` and `-` move between."""

SPARE_WHEN_PAINTED = 0.25
"""A swarm started from a painting gets this share of spare robots, to recruit on re-edits."""

IDLE_WAIT_MS = 250
"""How long an idle tick waits for an event; any event ends the wait at once."""

HUD_HEIGHT = 48
HUD_BACK = (38, 40, 46)
HUD_TEXT = (235, 235, 235)
HUD_DIM = (150, 155, 165)
HELP = (
    "Space pause   . step   + - speed   r restart   e edit   x fault tool   "
    "g l o overlays   F12 screenshot   q quit"
)
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
        pygame.font.init()
        pygame.display.set_caption(f"swarmshape - {title}")
        self.screen = pygame.display.set_mode(size, pygame.RESIZABLE)
        self.font = pygame.font.Font(None, 22)
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
        """Nothing changes unless the user acts: no swarm yet, paused, out of steps, or the
        run finished (formed, stranded, or a local program gone quiet, with no fault still to
        come) with every robot at rest and none wandering."""
        runner = self.runner
        if runner is None or self.paused or runner.out_of_steps:
            return True
        swarm = runner.swarm
        moving = np.isin(swarm.state, (MOVING, WANDERING)).any() or swarm.ahead.any()
        return runner.finished and not moving

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
        elif event.type == pygame.VIDEORESIZE:
            self.screen = pygame.display.set_mode(event.size, pygame.RESIZABLE)
        elif event.type == pygame.KEYDOWN and event.key == pygame.K_F12:
            self.notice = f"saved {self.screenshot()}"
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
        program = program_of(self.swarm)
        if program is None:
            self.notice = "no local program: overlays show a local program's values and links"
            return
        if name in self.overlays:
            self.overlays.discard(name)
            self.notice = f"{name} overlay off"
            return
        self.overlays.add(name)
        self.notice = f"{name} overlay on"
        if name == "values" and program.shown is None:
            self.notice += f": {program.name} shows no memory slot (Program.shown)"
        elif name == "values" and self.renderer.fit(self._world_area())[0] < VALUE_MIN_CELL:
            self.notice += ": cells too small to read, enlarge the window"
        elif name == "error" and program.estimate(self.swarm.driver.memory) is None:
            self.notice += f": {program.name} does not localise (Program.estimate)"

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
        """Save the window as PNG (atomically) and return its path."""
        step = 0 if self.swarm is None else self.swarm.step_count
        stem = Path(self.title).stem.replace(" ", "-")
        path = self.screenshots / f"swarmshape-{stem}-{step}.png"
        atomic_write(path, lambda tmp: pygame.image.save(self.screen, tmp))
        print(f"screenshot: {path}")
        return path

    def _world_area(self) -> pygame.Rect:
        width, height = self.screen.get_size()
        return pygame.Rect(0, HUD_HEIGHT, width, max(1, height - HUD_HEIGHT))

    def draw(self) -> None:
        area = self._world_area()
        self.renderer.draw(self.screen, self.swarm, area, self.overlays)
        if not self.editing:
            self._legend(area)
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
                for row, line in enumerate(HELP_LINES):
                    self._text(line, (panel.x + 10, panel.y + 6 + 22 * row), HUD_TEXT)
        width = self.screen.get_width()
        self.screen.fill(HUD_BACK, (0, 0, width, HUD_HEIGHT))
        self._text(self.status(), (10, 6), HUD_TEXT)
        self._text(self._second_line(), (10, 27), HUD_DIM)

    def _legend(self, area: pygame.Rect) -> None:
        """The local program's state colours, in the arena's bottom-left corner."""
        entries = legend(self.swarm)
        if not entries:
            return
        width = max(self.font.size(name)[0] for name, _ in entries) + 38
        panel = pygame.Rect(0, 0, width, 20 * len(entries) + 8)
        panel.bottomleft = (area.left + 8, area.bottom - 8)
        self.screen.fill(HUD_BACK, panel)
        for row, (name, colour) in enumerate(entries):
            y = panel.y + 5 + 20 * row
            self.screen.fill(colour, (panel.x + 8, y + 2, 14, 14))
            self._text(name, (panel.x + 30, y + 1), HUD_TEXT)

    def _help_panel(self, area: pygame.Rect) -> pygame.Rect:
        """The corner of `area` where the help covers the fewest seeds, then painted cells."""
        width = max(self.font.size(line)[0] for line in HELP_LINES) + 20
        panel = pygame.Rect(0, 0, width, 22 * len(HELP_LINES) + 10)
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

    def _second_line(self) -> str:
        if not self.editing:
            return self.notice or HELP
        editor = self.editor
        return editor.prompt() or editor.message or "h help   Enter: hand the shape to the swarm"

    def status(self) -> str:
        if self.editing:
            return self.editor.status()
        swarm = self.swarm
        settled = int((swarm.state == SETTLED).sum())
        done = swarm.completed_at
        formed = f"   formed at step {max(done)}" if None not in done else ""
        paused = "   PAUSED" if self.paused else ""
        missing = len(swarm.filled) - len(swarm.cell)
        if missing > 0:
            formed += f"   {missing} agents short"
        limit = f"/{self.runner.max_steps}"
        if self.out_of_steps:
            formed += "   max steps reached"
        if swarm.faults.lost:
            formed += f"   lost {swarm.faults.lost}"
        if self.fault_tool:
            formed += "   FAULT TOOL"
        if self.overlays and program_of(swarm) is not None:
            formed += "   showing " + " ".join(sorted(self.overlays))
        return (
            f"step {swarm.step_count}{limit}   settled {settled}/{len(swarm.filled)}   "
            f"coverage {100 * swarm.filled.mean():.1f}%   {self.speed:g} steps/frame   "
            f"{'idle' if self.idle else f'{self.clock.get_fps():.0f} FPS'}   "
            f"seed {swarm.seed}{formed}{paused}"
        )

"""The window: main loop, keys, heads-up display, screenshots.

Each call of `Viewer.tick` handles pending events, advances the simulation by the current
speed, and draws one frame, so tests can post events and drive it frame by frame under
``SDL_VIDEODRIVER=dummy``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pygame

from swarmshape.files import atomic_write
from swarmshape.render import Renderer
from swarmshape.swarm import State, Swarm

SPEEDS = (0.125, 0.25, 0.5, 1, 2, 4, 8, 16, 32, 64, 128, 256)
"""Simulation steps per frame that `+` and `-` move between."""

HUD_HEIGHT = 48
HUD_BACK = (38, 40, 46)
HUD_TEXT = (235, 235, 235)
HUD_DIM = (150, 155, 165)
HELP = "Space pause   . step   + - speed   r restart   F12 screenshot   q quit"


class Viewer:
    """A resizable window showing one run; `new_swarm` builds (and rebuilds on `r`) the run."""

    def __init__(
        self,
        new_swarm: Callable[[], Swarm],
        *,
        title: str,
        size: tuple[int, int] = (1280, 800),
        speed: float = 8,
        fps: int = 60,
        screenshots: Path = Path(),
    ) -> None:
        pygame.display.init()  # not pygame.init(): no sound, so no audio device needed
        pygame.font.init()
        pygame.display.set_caption(f"swarmshape - {title}")
        self.screen = pygame.display.set_mode(size, pygame.RESIZABLE)
        self.font = pygame.font.Font(None, 22)
        self.clock = pygame.time.Clock()
        self.title = title
        self.new_swarm = new_swarm
        self.swarm = new_swarm()
        self.renderer = Renderer(self.swarm.world)
        self.speed_index = min(range(len(SPEEDS)), key=lambda i: abs(SPEEDS[i] - speed))
        self.fps = fps
        self.screenshots = screenshots
        self.paused = False
        self.running = True
        self.notice = ""
        self._budget = 0.0

    @property
    def speed(self) -> float:
        return SPEEDS[self.speed_index]

    def run(self) -> None:
        while self.tick():
            pass
        pygame.quit()

    def tick(self) -> bool:
        """One frame: events, simulation, drawing. Returns False once the user quit."""
        for event in pygame.event.get():
            self.handle(event)
        if not self.paused:
            self._budget += self.speed
            while self._budget >= 1:
                self.swarm.step()
                self._budget -= 1
        self.draw()
        pygame.display.flip()
        self.clock.tick(self.fps)
        return self.running

    def handle(self, event: pygame.event.Event) -> None:
        if event.type == pygame.QUIT:
            self.running = False
        elif event.type == pygame.VIDEORESIZE:
            self.screen = pygame.display.set_mode(event.size, pygame.RESIZABLE)
        elif event.type == pygame.KEYDOWN:
            self._key(event)

    def _key(self, event: pygame.event.Event) -> None:
        key = event.key
        if key in (pygame.K_ESCAPE, pygame.K_q):
            self.running = False
        elif key == pygame.K_SPACE:
            self.paused = not self.paused
        elif key == pygame.K_PERIOD:
            self.paused = True
            self.swarm.step()
        elif key in (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS):
            self.speed_index = min(self.speed_index + 1, len(SPEEDS) - 1)
        elif key in (pygame.K_MINUS, pygame.K_KP_MINUS):
            self.speed_index = max(self.speed_index - 1, 0)
        elif key == pygame.K_r:
            self.swarm = self.new_swarm()
            self.notice = f"restarted with seed {self.swarm.seed}"
        elif key == pygame.K_F12:
            self.notice = f"saved {self.screenshot()}"

    def screenshot(self) -> Path:
        """Save the window as PNG (atomically) and return its path."""
        path = self.screenshots / f"swarmshape-{Path(self.title).stem}-{self.swarm.step_count}.png"
        atomic_write(path, lambda tmp: pygame.image.save(self.screen, tmp))
        print(f"screenshot: {path}")
        return path

    def draw(self) -> None:
        width, height = self.screen.get_size()
        world_area = pygame.Rect(0, HUD_HEIGHT, width, max(1, height - HUD_HEIGHT))
        self.renderer.draw(self.screen, self.swarm, world_area)
        self.screen.fill(HUD_BACK, (0, 0, width, HUD_HEIGHT))
        self.screen.blit(self.font.render(self.status(), True, HUD_TEXT), (10, 6))
        self.screen.blit(self.font.render(self.notice or HELP, True, HUD_DIM), (10, 27))

    def status(self) -> str:
        swarm = self.swarm
        settled = int((swarm.state == State.SETTLED).sum())
        targets = len(swarm.filled)
        done = swarm.completed_at
        formed = f"   formed at step {max(done)}" if None not in done else ""
        paused = "   PAUSED" if self.paused else ""
        speed = f"{self.speed:g}"
        return (
            f"step {swarm.step_count}   settled {settled}/{targets}   "
            f"coverage {100 * swarm.filled.mean():.1f}%   {speed} steps/frame   "
            f"{self.clock.get_fps():.0f} FPS   seed {swarm.seed}{formed}{paused}"
        )

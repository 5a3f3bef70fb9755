"""Drawing an environment's swarm with the window's own renderer (`swarmshape.ui.render`),
loaded only when a render mode is chosen, so a headless environment never imports pygame.

``"rgb_array"``: `render()` returns the frame as a numpy array ``(height, width, 3)`` uint8,
drawn offscreen (no window; set ``SDL_VIDEODRIVER=dummy`` where there is no display).
``"human"``: a pygame window, redrawn at every reset and step and paced to ``render_fps``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmshape.core.swarm import Swarm

FPS = 30
RENDER_MODES = ("human", "rgb_array")


class Screen:
    def __init__(self, mode: str | None, size: tuple[int, int] = (640, 400)) -> None:
        if mode is not None and mode not in RENDER_MODES:
            raise ValueError(f"render_mode must be one of {RENDER_MODES} or None, got {mode!r}")
        self.mode = mode
        self.size = size
        self.window: Any = None
        self.clock: Any = None
        self.renderer: Any = None

    def render(self, swarm: Swarm | None) -> np.ndarray | None:
        """What an environment's ``render()`` returns: the frame, or None (drawn in the window,
        or no render mode, or nothing to draw yet)."""
        if swarm is None or self.mode is None:
            return None
        if self.mode == "rgb_array":
            return self.frame(swarm)
        self.show(swarm)
        return None

    def update(self, swarm: Swarm) -> None:
        """After a reset or a step: the window follows the swarm."""
        if self.mode == "human":
            self.show(swarm)

    def frame(self, swarm: Swarm) -> np.ndarray:
        from swarmshape.ui.render import Renderer, frame

        if self.renderer is None or self.renderer.world is not swarm.world:
            self.renderer = Renderer(swarm.world)
        return frame(swarm, self.size, self.renderer)

    def show(self, swarm: Swarm) -> None:
        """Draw `swarm` in the window (opened on first use)."""
        import pygame

        from swarmshape.ui.render import Renderer

        if self.window is None:
            pygame.display.init()
            pygame.display.set_caption("swarmshape environment")
            self.window = pygame.display.set_mode(self.size)
            self.clock = pygame.time.Clock()
        if self.renderer is None or self.renderer.world is not swarm.world:
            self.renderer = Renderer(swarm.world)
        pygame.event.pump()
        self.renderer.draw(self.window, swarm)
        pygame.display.flip()
        self.clock.tick(FPS)

    def close(self) -> None:
        if self.window is not None:
            import pygame

            pygame.display.quit()
            self.window = None

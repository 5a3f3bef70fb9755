"""Drawing a learning environment's swarm with the window's own renderer; the environment
loads this module only when a render mode is chosen, so a headless one never imports pygame.

``"rgb_array"``: `render()` returns the frame as a numpy array ``(height, width, 3)`` uint8,
drawn offscreen (no window; set ``SDL_VIDEODRIVER=dummy`` where there is no display).
``"human"``: a pygame window, redrawn at every reset and step and paced to ``render_fps``.
"""

from __future__ import annotations

import numpy as np
import pygame

from swarmshape.core.swarm import Swarm
from swarmshape.ui.render import Renderer, frame


class Screen:
    """A render mode's output: frames as arrays, or a window paced to `fps`."""

    def __init__(self, mode: str, size: tuple[int, int], fps: int) -> None:
        self.mode = mode
        self.size = size
        self.fps = fps
        self.window: pygame.Surface | None = None
        self.clock = pygame.time.Clock()
        self.renderer: Renderer | None = None

    def render(self, swarm: Swarm | None) -> np.ndarray | None:
        """What an environment's ``render()`` returns: the frame, or None (drawn in the window,
        or nothing to draw yet)."""
        if swarm is None:
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
        return frame(swarm, self.size, self._renderer(swarm))

    def show(self, swarm: Swarm) -> None:
        """Draw `swarm` in the window (opened on first use)."""
        if self.window is None:
            pygame.display.init()
            pygame.display.set_caption("swarmshape environment")
            self.window = pygame.display.set_mode(self.size)
        pygame.event.pump()
        self._renderer(swarm).draw(self.window, swarm)
        pygame.display.flip()
        self.clock.tick(self.fps)

    def _renderer(self, swarm: Swarm) -> Renderer:
        if self.renderer is None or self.renderer.world is not swarm.world:
            self.renderer = Renderer(swarm.world)
        return self.renderer

    def close(self) -> None:
        if self.window is not None:
            pygame.display.quit()
            self.window = None

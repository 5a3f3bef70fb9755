"""Recording a run: an animation (GIF, WebP, APNG) or numbered PNG frames, drawn offscreen.

Frames are kept as small palette images; when a long run would pass `MAX_FRAMES`, every
other frame is dropped and the stride doubles, so the file stays a sane size.
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write
from swarmshape.ui.render import Renderer, frame

ANIMATIONS = {".gif": "GIF", ".webp": "WEBP", ".png": "PNG"}
MAX_FRAMES = 400
FRAME_SIZE = (640, 400)
FRAME_MS = 40


class Recorder:
    """Captures every `every`-th step of a swarm; `close` writes the files."""

    def __init__(
        self, animation: Path | None = None, frames: Path | None = None, every: int = 1
    ) -> None:
        if every < 1:
            raise InputError(f"--record-every must be at least 1, got {every}")
        if animation is not None and animation.suffix.lower() not in ANIMATIONS:
            raise InputError(
                f"{animation}: --record writes {', '.join(ANIMATIONS)} files; pick one of those"
            )
        if frames is not None:
            if frames.exists() and not frames.is_dir():
                raise InputError(f"{frames}: --frames needs a folder, and this is a file")
            frames.mkdir(parents=True, exist_ok=True)
        self.animation, self.frames, self.every = animation, frames, every
        self._images: list[Image.Image] = []
        self._renderer: Renderer | None = None
        self._last = -1

    def capture(self, swarm: Swarm, *, force: bool = False) -> None:
        """Draw the swarm if this step is one to keep (or `force`)."""
        if swarm.step_count == self._last or (swarm.step_count % self.every and not force):
            return
        self._last = swarm.step_count
        if self._renderer is None or self._renderer.world is not swarm.world:
            self._renderer = Renderer(swarm.world)
        image = Image.fromarray(frame(swarm, FRAME_SIZE, self._renderer)).quantize(colors=32)
        if self.frames is not None:
            path = self.frames / f"frame-{swarm.step_count:07d}.png"
            atomic_write(path, lambda tmp: image.save(tmp, format="PNG"))
        if self.animation is not None:
            self._images.append(image)
            if len(self._images) > MAX_FRAMES:
                self._images = self._images[::2]
                self.every *= 2

    def close(self, swarm: Swarm) -> None:
        """Write the animation (atomically), if one was asked for; `swarm` gives the last frame."""
        self.capture(swarm, force=True)  # a run rarely ends on the stride: keep its end too
        if self.animation is None or not self._images:
            return
        first, *rest = self._images
        options = {"save_all": True, "append_images": rest, "duration": FRAME_MS, "loop": 0}
        form = ANIMATIONS[self.animation.suffix.lower()]
        atomic_write(self.animation, lambda tmp: first.save(tmp, format=form, **options))

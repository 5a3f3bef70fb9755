"""Recording a run: an animation (GIF, WebP, APNG), an MP4 video, or numbered PNG frames,
drawn offscreen.

Each frame has a line of text with its step and coverage, so a frame read on its own says when
it was taken. Frames are kept as small palette images; when a long run would pass `MAX_FRAMES`
(fewer for large frames, see `FRAME_PIXELS`), every other frame is dropped and the stride
doubles, so the file and the memory it takes stay a sane size. An MP4 holds the same frames,
encoded as H.264 by the ffmpeg that the ``video`` extra's imageio-ffmpeg wheel ships.
"""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.io.files import OutputError, TemporaryFolder, atomic_write
from swarmshape.runs import Observer
from swarmshape.ui.render import Renderer, frame

ANIMATIONS = {".gif": "GIF", ".webp": "WEBP", ".png": "PNG", ".mp4": "MP4"}
VIDEO = ("-crf", "23", "-tune", "animation", "-movflags", "+faststart")
"""ffmpeg's H.264 options: its default quality, tuned for flat colours; playable while it
downloads."""
MAX_FRAMES = 400
FRAME_SIZE = (640, 400)
"""The default frame size (``--record-size``)."""
MIN_SIZE, MAX_SIZE = (64, 48), (4096, 4096)
FRAME_PIXELS = 256_000_000
"""Pixels an animation keeps in memory at most (one byte each): 400 frames of 640x400,
123 of 1920x1080."""
FRAME_MS = 40
FRAME_FILES = "frame-[0-9][0-9][0-9][0-9][0-9][0-9][0-9].png"
"""The names of frame files, and the only files in a frames folder this removes."""


class Recorder(Observer):
    """Captures every `every`-th step of a swarm; `close` writes the files. Frames are drawn
    into a temporary folder beside their folder and moved into it at `close`, where they
    replace an earlier run's frames, all of them; a run abandoned (`discard`) leaves the
    folder as it was."""

    def __init__(
        self,
        animation: Path | None = None,
        frames: Path | None = None,
        every: int = 1,
        size: tuple[int, int] = FRAME_SIZE,
    ) -> None:
        if every < 1:
            raise InputError(f"--record-every must be at least 1, got {every}")
        width, height = size
        if not (MIN_SIZE[0] <= width <= MAX_SIZE[0] and MIN_SIZE[1] <= height <= MAX_SIZE[1]):
            raise InputError(
                f"--record-size must be from {MIN_SIZE[0]}x{MIN_SIZE[1]} to "
                f"{MAX_SIZE[0]}x{MAX_SIZE[1]} pixels, got {width}x{height}"
            )
        if animation is not None and animation.suffix.lower() not in ANIMATIONS:
            raise InputError(
                f"{animation}: --record writes {', '.join(ANIMATIONS)} files; pick one of those"
            )
        if animation is not None and animation.suffix.lower() == ".mp4":
            _encoder(animation)  # refused now, not after the run
        if frames is not None:
            if frames.exists() and not frames.is_dir():
                raise InputError(f"{frames}: --frames needs a folder, and this is a file")
            frames = Path(os.path.realpath(frames))  # through a link
            self._unfinished = TemporaryFolder(frames)
        self.animation, self.frames, self.every, self.size = animation, frames, every, size
        self._keep = max(2, min(MAX_FRAMES, FRAME_PIXELS // (width * height)))
        self._images: list[Image.Image] = []
        self._written: set[str] = set()
        self._renderer: Renderer | None = None
        self._last = -1

    def capture(self, swarm: Swarm, *, force: bool = False) -> None:
        """Draw the swarm if this step is one to keep (or `force`)."""
        if swarm.step_count == self._last or (swarm.step_count % self.every and not force):
            return
        self._last = swarm.step_count
        if self._renderer is None or self._renderer.world is not swarm.world:
            self._renderer = Renderer(swarm.world)
        pixels = frame(swarm, self.size, self._renderer, caption(swarm))
        image = Image.fromarray(pixels).quantize(colors=32)
        if self.frames is not None:
            name = f"frame-{swarm.step_count:07d}.png"
            try:
                image.save(self._unfinished.path / name, format="PNG")
            except OSError as error:  # named where the user will look for it
                problem = error.strerror or error
                raise OutputError(f"{self.frames / name}: cannot write it ({problem})") from None
            self._written.add(name)
        if self.animation is not None:
            self._images.append(image)
            if len(self._images) > self._keep:
                self._images = self._images[::2]
                self.every *= 2

    def close(self, swarm: Swarm) -> None:
        """Write the animation (atomically), if one was asked for; `swarm` gives the last frame."""
        self.capture(swarm, force=True)  # a run rarely ends on the stride: keep its end too
        if self.frames is not None:
            self._unfinished.finish(FRAME_FILES)
        if self.animation is None or not self._images:
            return
        form = ANIMATIONS[self.animation.suffix.lower()]
        if form == "MP4":
            atomic_write(self.animation, self._video)
            return
        first, *rest = self._images
        options = {"save_all": True, "append_images": rest, "duration": FRAME_MS, "loop": 0}
        atomic_write(self.animation, lambda tmp: first.save(tmp, format=form, **options))

    def discard(self) -> None:
        """The run was abandoned: its frames go, and the folder is as it was."""
        if self.frames is not None:
            self._unfinished.discard()

    def _video(self, path: str) -> None:
        """The frames as an H.264 MP4 at the animations' pace, each padded to even sides
        (which H.264's colour format needs) by repeating its last row and column. ffmpeg runs
        here rather than through imageio-ffmpeg's writer, which neither reads ffmpeg's exit
        status nor keeps its messages off the terminal: on a full disk it kept a truncated
        file, with ffmpeg's lines on stderr."""
        width, height = self.size
        even = (width + width % 2, height + height % 2)
        command = [
            _encoder(self.animation).get_ffmpeg_exe(), "-y", "-v", "error",
            "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{even[0]}x{even[1]}",
            "-r", f"{1000 / FRAME_MS:g}", "-i", "-", "-an",
            "-vcodec", "libx264", "-pix_fmt", "yuv420p", *VIDEO, path,
        ]  # fmt: skip
        with tempfile.TemporaryFile() as said:
            ffmpeg = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=said)
            assert ffmpeg.stdin is not None
            try:
                for image in self._images:
                    pixels = np.asarray(image.convert("RGB"))
                    padding = ((0, even[1] - height), (0, even[0] - width), (0, 0))
                    ffmpeg.stdin.write(np.pad(pixels, padding, mode="edge").tobytes())
                ffmpeg.stdin.close()
            except BrokenPipeError:  # ffmpeg stopped: what it said tells why
                pass
            except BaseException:
                ffmpeg.kill()
                raise
            finally:
                status = ffmpeg.wait()
            if status != 0:
                said.seek(0)
                lines = said.read().decode(errors="replace").strip().splitlines() or [
                    f"exit status {status}"
                ]
                # the first line says why; its tags name ffmpeg's parts ("[libx264 @ 0x55...]")
                raise OSError("ffmpeg: " + re.sub(r"^(\[[^]]*\] *)+", "", lines[0]))


def _encoder(path: Path):
    """imageio-ffmpeg, or one clear line saying how to get it."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InputError(
            f"{path}: --record .mp4 needs the video extra: pip install 'swarmshape[video]'"
        ) from None
    return imageio_ffmpeg


def caption(swarm: Swarm) -> str:
    """The text line of a recorded frame."""
    return f"step {swarm.step_count}   coverage {100 * swarm.filled.mean():.1f}%"

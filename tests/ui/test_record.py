"""Recordings: frame size, and the step and coverage written into every frame."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from swarmshape.errors import InputError
from swarmshape.ui.record import Recorder, caption
from swarmshape.ui.render import frame
from tests.conftest import SHAPES, grid_from, make_swarm

SHAPE = grid_from("""
####
#...
""")


def frames_of(folder) -> list[np.ndarray]:
    return [np.asarray(Image.open(p).convert("RGB")) for p in sorted(folder.glob("*.png"))]


def test_frames_take_the_size_asked_for(tmp_path):
    swarm = make_swarm(SHAPE, seed=1)
    for size, folder in (((320, 200), "small"), (None, "default")):
        options = {} if size is None else {"size": size}
        recorder = Recorder(frames=tmp_path / folder, **options)
        recorder.capture(swarm)
        recorder.close(swarm)
        (image,) = frames_of(tmp_path / folder)
        assert image.shape[:2] == ((200, 320) if size else (400, 640))


def test_every_frame_shows_its_step_and_coverage(tmp_path):
    swarm = make_swarm(SHAPE, seed=1)
    recorder = Recorder(frames=tmp_path, size=(320, 200), every=10)
    recorder.capture(swarm)
    while swarm.step_count < 10:
        swarm.step()
    recorder.capture(swarm)
    assert caption(swarm) == f"step 10   coverage {100 * swarm.filled.mean():.1f}%"
    first, last = frames_of(tmp_path)
    strip = slice(0, 12)
    assert not np.array_equal(first[strip], last[strip]), "the text line differs per step"
    assert len(np.unique(last[strip].reshape(-1, 3), axis=0)) > 2, "text, not a plain band"
    assert frame(swarm, (320, 200)).shape == (200, 320, 3)  # as examples and notebooks use it


@pytest.mark.parametrize("size", [(0, 400), (640, 10), (100_000, 400)])
def test_absurd_sizes_are_refused_in_one_line(tmp_path, size):
    with pytest.raises(InputError, match="--record-size"):
        Recorder(tmp_path / "run.gif", size=size)


def test_a_frames_folder_named_by_a_dangling_link_is_made_at_its_target(tmp_path):
    """Found by the fuzz: --frames LINK, a link to a folder not made yet, was an internal
    error (mkdir of the link's own name); like any output, it is written through the link."""
    from swarmshape.cli import main

    link = tmp_path / "frames"
    link.symlink_to(tmp_path / "real")
    assert (
        main([str(SHAPES / "line.png"), "--headless", "--max-steps", "2", "--frames", str(link)])
        == 3
    )
    assert link.is_symlink() and len(list((tmp_path / "real").glob("frame-*.png"))) == 3

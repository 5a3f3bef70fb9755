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
    recorder.close(swarm)
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


def decoded(path) -> list[np.ndarray]:
    """Every frame of a video, as RGB arrays."""
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = reader.__next__()
    width, height = meta["size"]
    return [np.frombuffer(raw, np.uint8).reshape(height, width, 3) for raw in reader]


def test_an_mp4_holds_the_frames_a_gif_holds(tmp_path):
    from swarmshape.cli import main

    common = [str(SHAPES / "line.png"), "--headless", "--seed", "1", "--record-every", "4"]
    assert main([*common, "--record", str(tmp_path / "run.gif")]) == 0
    assert main([*common, "--record", str(tmp_path / "run.mp4")]) == 0
    with Image.open(tmp_path / "run.gif") as gif:
        first = np.asarray(gif.convert("RGB"))
        count = gif.n_frames
    video = decoded(tmp_path / "run.mp4")
    assert len(video) == count > 2 and video[0].shape == (400, 640, 3)
    assert np.abs(video[0].astype(int) - first).mean() < 3, "the same picture, lossily kept"
    assert not np.array_equal(video[0], video[-1])


def test_an_mp4_of_odd_size_is_padded_to_even_sides(tmp_path):
    swarm = make_swarm(SHAPE, seed=1)
    recorder = Recorder(tmp_path / "odd.mp4", size=(321, 201))
    recorder.capture(swarm)
    swarm.step()
    recorder.close(swarm)
    assert [frame.shape for frame in decoded(tmp_path / "odd.mp4")] == [(202, 322, 3)] * 2


def test_mp4_without_the_video_extra_is_one_line_before_the_run(tmp_path, monkeypatch, capsys):
    import sys

    from swarmshape.cli import main

    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # as if not installed
    out = tmp_path / "run.mp4"
    assert main([str(SHAPES / "line.png"), "--headless", "--record", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "pip install 'swarmshape[video]'" in lines[0], lines
    assert captured.out == "" and not out.exists(), "refused before anything ran"


def test_an_mp4_that_ffmpeg_fails_to_write_is_one_line_and_keeps_the_old_file(
    tmp_path, monkeypatch, capfd
):
    """On a full disk ffmpeg stopped at the header or the trailer: imageio-ffmpeg's writer did
    not notice, and a truncated file replaced the user's. Here ffmpeg fails as surely, on an
    option it refuses."""
    from swarmshape.cli import main
    from swarmshape.ui import record

    out = tmp_path / "run.mp4"
    out.write_bytes(b"the user's video")
    monkeypatch.setattr(record, "VIDEO", ("-crf", "not-a-number"))
    command = [str(SHAPES / "line.png"), "--headless", "--seed", "1", "--record", str(out)]
    assert main([*command, "--force"]) == 2
    captured = capfd.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert line.startswith(f"swarmshape: error: {out}: cannot write it (ffmpeg: "), line
    assert "[" not in line, "ffmpeg's source tag dropped"
    assert out.read_bytes() == b"the user's video"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["run.mp4"], "no temporary left"

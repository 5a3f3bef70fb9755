"""Recording, traces, saved states and start positions, through the real command line."""

from __future__ import annotations

import csv
import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from swarmshape.cli import main
from swarmshape.errors import InputError, Terminated
from swarmshape.io import files
from swarmshape.io.bitmap import load_grid
from swarmshape.io.scenario import read_start_cells
from swarmshape.session import SHADES, ended_by_signals
from swarmshape.ui.render import SEED_GREEN
from tests import pictures
from tests.conftest import SHAPES, grid_from, make_swarm, world_of

HORSESHOE = str(SHAPES / "horseshoe.png")


def run(*args: str) -> None:
    """A run that forms its shape (exit 0); one stopped early by --max-steps exits 3."""
    assert main([*args]) == (3 if "--max-steps" in args else 0)


def test_a_gif_has_the_expected_frames_and_its_first_shows_the_seeds(tmp_path):
    gif = tmp_path / "run.gif"
    run(HORSESHOE, "--headless", "--seed", "2", "--record", str(gif), "--record-every", "5",
        "--metrics", str(tmp_path / "m.json"))  # fmt: skip
    steps = json.loads((tmp_path / "m.json").read_text())["steps"]
    with Image.open(gif) as image:
        expected = steps // 5 + 1 + (steps % 5 > 0)  # step 0, every 5th, and the last
        assert image.n_frames == expected
        image.seek(0)
        colours = {rgb for _, rgb in image.convert("RGB").getcolors(1 << 16)}
    assert any(
        all(abs(c - s) < 12 for c, s in zip(rgb, SEED_GREEN, strict=True)) for rgb in colours
    )


@pytest.mark.parametrize("suffix", [".webp", ".png"])
def test_webp_and_apng_are_animations_too(tmp_path, suffix):
    out = tmp_path / f"run{suffix}"
    run(str(SHAPES / "line.png"), "--headless", "--seed", "1", "--record", str(out))
    with Image.open(out) as image:
        assert getattr(image, "n_frames", 1) > 1


def test_frames_go_to_a_folder_as_numbered_pngs(tmp_path):
    run(str(SHAPES / "line.png"), "--headless", "--seed", "1", "--frames", str(tmp_path / "f"),
        "--record-every", "10")  # fmt: skip
    names = sorted(p.name for p in (tmp_path / "f").iterdir())
    assert names[0] == "frame-0000000.png" and names[1] == "frame-0000010.png"


def test_the_last_trace_row_equals_the_metrics_file(tmp_path):
    trace, metrics = tmp_path / "t.csv", tmp_path / "m.json"
    run(str(SHAPES / "two-squares.toml"), "--headless", "--seed", "3", "--strategy", "optimal",
        "--trace", str(trace), "--trace-every", "7", "--metrics", str(metrics))  # fmt: skip
    rows = list(csv.DictReader(trace.open()))
    result = json.loads(metrics.read_text())
    last = rows[-1]
    assert int(last["step"]) == result["steps_run"]
    assert float(last["coverage"]) == result["coverage"] and float(last["iou"]) == result["iou"]
    assert int(last["overlaps"]) == result["overlaps"]
    for group in result["groups"]:
        assert float(last[f"{group['name']}.coverage"]) == group["coverage"]
    assert [int(r["step"]) for r in rows[:3]] == [0, 7, 14]


def test_save_then_load_then_continue_equals_an_uninterrupted_run(tmp_path):
    common = [str(SHAPES / "ring.png"), "--headless", "--seed", "4", "--cells", "16"]
    run(*common, "--strategy", "random", "--metrics", str(tmp_path / "full.json"))
    run(*common, "--strategy", "random", "--max-steps", "40", "--save-state",
        str(tmp_path / "half.state"))  # fmt: skip
    run("--load-state", str(tmp_path / "half.state"), "--headless", "--metrics",
        str(tmp_path / "resumed.json"))  # fmt: skip
    assert (tmp_path / "full.json").read_bytes() == (tmp_path / "resumed.json").read_bytes()


def test_start_positions_come_from_a_csv(tmp_path):
    world = world_of(grid_from("###"))
    cells = world.start_cells()[[0, 5, 9]]
    path = tmp_path / "start.csv"
    path.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in cells.tolist()))
    assert read_start_cells(path, world).tolist() == cells.tolist()
    rows = "".join(f"{x}, {y}\n" for x, y in cells.tolist())
    path.write_text("\ufeffx, y\n" + rows, encoding="utf-8")  # a BOM and spaces, as sheets write
    assert read_start_cells(path, world).tolist() == cells.tolist()
    path.write_text("x,y\n0,0\n")
    with pytest.raises(InputError, match="1 start positions for 3 robots"):
        read_start_cells(path, world)
    path.write_text("x,y\n" + "0,0\n" * 100_000)  # counted, not kept
    with pytest.raises(InputError, match="100000 start positions for 3 robots"):
        read_start_cells(path, world)
    target = world.targets[0]
    path.write_text("x,y\n" + "".join(f"{x},{y}\n" for x, y in [*cells[:2].tolist(), target]))
    with pytest.raises(InputError, match="row 4"):
        read_start_cells(path, world)


def test_outputs_are_not_overwritten_without_force(tmp_path):
    out = tmp_path / "m.json"
    out.write_text("precious")
    assert main([str(SHAPES / "line.png"), "--headless", "--metrics", str(out)]) == 2
    assert out.read_text() == "precious"
    run(str(SHAPES / "line.png"), "--headless", "--metrics", str(out), "--force")
    assert json.loads(out.read_text())["coverage"] == 1.0


def test_a_resumed_state_may_be_saved_over_itself(tmp_path):
    state = tmp_path / "s.state"
    run(str(SHAPES / "line.png"), "--headless", "--max-steps", "5", "--save-state", str(state))
    run("--load-state", str(state), "--headless", "--max-steps", "9", "--save-state", str(state))


def test_preview_prints_the_shape_and_runs_nothing(tmp_path, capsys):
    assert main([HORSESHOE, "--preview", "--metrics", str(tmp_path / "m.json")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("horseshoe: 90 cells, 12x12, 90 robots, scale 1.00; left, its ")
    assert lines[1] == "#" * 12 + "  " + "#" * 12 and len(lines) == 13, "the picture beside"
    assert not (tmp_path / "m.json").exists()


def test_preview_of_a_saved_run_shows_its_shape_not_the_default_one(tmp_path, capsys):
    """Found while fuzzing: --load-state s.state --preview printed the bundled horseshoe."""
    state = tmp_path / "s.state"
    run(str(SHAPES / "line.png"), "--headless", "--max-steps", "5", "--save-state", str(state))
    capsys.readouterr()
    assert main(["--load-state", str(state), "--preview"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("line: 16 cells") and len(lines) == 2


def test_fit_agents_sizes_the_shape_to_the_robots(tmp_path):
    out = tmp_path / "m.json"
    assert main([HORSESHOE, "--agents", "400", "--fit", "agents", "--preview"]) == 0
    assert main([HORSESHOE, "--agents", "400", "--fit", "agents", "--headless", "--seed", "2",
                 "--metrics", str(out)]) == 0  # fmt: skip
    metrics = json.loads(out.read_text())
    assert 300 < metrics["targets"] <= 400 and metrics["coverage"] == 1.0


def test_many_more_robots_than_cells_is_a_warning_naming_fit(capsys):
    assert main([HORSESHOE, "--agents", "400", "--preview"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--fit agents" in err[0] and err[0].startswith("swarmshape: warning")


def test_a_run_with_two_warnings_shows_the_first_in_one_line(tmp_path, capsys):
    """Found by the fuzz: --cells 1 --agents 5 printed two warning lines (the picture became
    one cell; five robots for it), where a run says at most one."""
    picture = np.full((8, 8), 255, dtype=np.uint8)
    picture[2:4, 2:4] = 0
    Image.fromarray(picture).save(tmp_path / "dot.png")
    assert main([str(tmp_path / "dot.png"), "--cells", "1", "--agents", "5", "--preview"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == ["swarmshape: warning: " + f"{tmp_path / 'dot.png'}: the whole picture became "
                   "1 cell; raise --cells to 2 to keep it"]  # fmt: skip


def test_progress_off_a_terminal_is_a_line_every_few_seconds(monkeypatch, capsys):
    from swarmshape.experiments import progress

    clock = iter([0.0, 3.0, 11.0, 12.0, 25.0])
    monkeypatch.setattr(progress.time, "monotonic", lambda: next(clock))
    bar = progress.ProgressBar()  # stderr is captured, not a terminal
    for step in range(4):
        bar.show(step / 4, f"step {step}")
    bar.done()
    assert capsys.readouterr().err == "swarmshape: step 1\nswarmshape: step 3\n"


def test_a_window_run_stops_at_max_steps_and_writes_its_metrics(tmp_path, monkeypatch):
    import pygame

    from swarmshape.ui.viewer import Viewer

    real_tick = Viewer.tick

    def tick_then_quit(self):
        if self.swarm is not None and self.swarm.step_count >= 30:
            pygame.event.post(pygame.event.Event(pygame.QUIT))
        return real_tick(self)

    monkeypatch.setattr(Viewer, "tick", tick_then_quit)
    out = tmp_path / "m.json"
    assert main([HORSESHOE, "--seed", "2", "--max-steps", "30", "--metrics", str(out)]) == 0
    metrics = json.loads(out.read_text())
    assert metrics["steps_run"] == 30 and metrics["steps"] is None


def test_positions_are_exported_per_step_as_arrays_or_rows(tmp_path):
    import numpy as np

    npz, rows = tmp_path / "p.npz", tmp_path / "p.csv"
    common = [str(SHAPES / "line.png"), "--headless", "--seed", "1"]
    run(*common, "--positions", str(npz), "--positions-every", "5")
    run(*common, "--positions", str(rows), "--positions-every", "5")
    with np.load(npz) as saved:
        steps, position = saved["step"], saved["position"]
        assert steps[0] == 0 and (np.diff(steps)[:-1] == 5).all()
        assert position.shape == (len(steps), 16, 2) and saved["group"].shape == (16,)
    table = list(csv.DictReader(rows.open()))
    assert len(table) == 16 * len(steps)
    last = [r for r in table if int(r["step"]) == steps[-1]]
    assert np.allclose([[float(r["x"]), float(r["y"])] for r in last], position[-1], atol=1e-5)


def test_a_strategy_file_in_the_working_folder_runs_with_the_installed_command(tmp_path):
    import os
    import subprocess
    import sys

    (tmp_path / "my_strategies.py").write_text(
        "from swarmshape.strategies.concurrent import Greedy\n"
        "class NearestFirst(Greedy):\n    name = 'nearest-first'\n"
    )
    command = Path(sys.executable).parent / "swarmshape"
    result = subprocess.run(
        [str(command), str(SHAPES / "line.png"), "--headless", "--strategy",
         "my_strategies.py:NearestFirst"],
        capture_output=True, text=True, cwd=tmp_path,
        env={**os.environ, "SDL_VIDEODRIVER": "dummy"},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "nearest-first" in result.stdout


def test_the_editor_names_no_seed_while_nothing_runs(tmp_path, monkeypatch, capsys):
    import pygame

    from swarmshape.ui.viewer import Viewer

    real_tick = Viewer.tick

    def quit_at_once(self):
        pygame.event.post(pygame.event.Event(pygame.QUIT))
        return real_tick(self)

    monkeypatch.setattr(Viewer, "tick", quit_at_once)
    assert main(["edit", str(tmp_path / "new.png")]) == 0
    assert "seed" not in capsys.readouterr().out
    assert main([str(SHAPES / "line.png"), "--seed", "5"]) == 0
    assert capsys.readouterr().out.startswith("seed 5\n"), "a window run names its seed"


def test_preview_shows_a_users_picture_beside_the_shape_it_keeps(tmp_path, capsys):
    """Issue 34: a word at the default size, its letters beside the cells that draw them."""
    path = pictures.word(tmp_path / "word.png")
    assert main([str(path), "--preview"]) == 0
    out, err = capsys.readouterr()
    head, *rows = out.splitlines()
    grid = load_grid(path)
    assert head.startswith(f"word: {grid.sum()} cells, {grid.shape[1]}x{grid.shape[0]}")
    assert err == "" and len(rows) == grid.shape[0]
    shape = ["".join("#" if cell else "." for cell in row) for row in grid.tolist()]
    for row, cells in zip(rows, shape, strict=True):
        picture, shown = row[: -len(cells) - 2], row[-len(cells) :]
        assert shown == cells and len(picture) == len(cells) and set(picture) <= set(SHADES)
    assert main([str(path), "--preview", "--cells", "32"]) == 0
    assert "raise --cells to" in capsys.readouterr().err


def test_a_signal_that_a_library_turns_into_its_own_error_still_ends_the_run():
    """The fuzz (seed 39) sent SIGTERM while pygame loaded a font: pygame's file reader turned
    `Terminated` into "TypeError: not a file object", and the run ended as an internal error
    (exit 1) instead of 143."""
    with pytest.raises(Terminated) as ended, ended_by_signals():
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)  # the handler raises here, at once
        except Terminated:
            raise TypeError("not a file object") from None  # as pygame's reader does
    assert ended.value.code == 128 + signal.SIGTERM


def test_a_signal_as_an_output_makes_its_temporary_leaves_nothing_behind(tmp_path, monkeypatch):
    """The fuzz (seed 40) sent SIGTERM just as a run made its frames' temporary folder, before
    the run had it to discard: the folder stayed. Whatever temporaries a command made and did
    not rename go as it ends."""
    made = files.TemporaryFolder.__init__

    def struck(self: files.TemporaryFolder, target: Path) -> None:
        made(self, target)
        raise Terminated(128 + signal.SIGTERM)

    monkeypatch.setattr(files.TemporaryFolder, "__init__", struck)
    with pytest.raises(Terminated):
        main([HORSESHOE, "--headless", "--max-steps", "5", "--frames", str(tmp_path / "out")])
    assert list(tmp_path.iterdir()) == []


def test_a_signal_that_c_code_swallows_still_ends_the_run():
    """The fuzz (seed 42) sent SIGTERM while numba compiled a kernel: raised inside its ctypes
    callback, `Terminated` was printed as "Exception ignored" with a traceback, and the run went
    on to its end (exit 3). The run's watch ends it at its next step, or as the block ends."""
    import ctypes

    def callback() -> None:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises here, and ctypes swallows it

    swallowing = ctypes.CFUNCTYPE(None)(callback)
    swarm = make_swarm(np.ones((2, 2), dtype=bool))
    with pytest.raises(Terminated) as ended, ended_by_signals():
        swallowing()
    assert ended.value.code == 128 + signal.SIGTERM
    with pytest.raises(Terminated), ended_by_signals() as watch:
        swallowing()
        with pytest.raises(Terminated):
            watch.capture(swarm)  # the run's next step

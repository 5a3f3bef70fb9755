"""Outputs: written atomically, through symlinks, never over pipes or devices, never twice,
and a failure to write is one line; inputs that are not regular files are refused at once."""

from __future__ import annotations

import csv
import errno
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from swarmshape.cli import main
from swarmshape.config import configure
from swarmshape.errors import InputError
from swarmshape.io import files
from swarmshape.io.files import OutputError, atomic_write, check_output
from swarmshape.runs import Runner, build, resume
from swarmshape.session import stopped_by_ctrl_c
from tests.conftest import SHAPES

LINE = str(SHAPES / "line.png")


def test_a_symlinked_output_is_written_through_and_stays_a_link(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert main([LINE, "--headless", "--metrics", str(link), "--force"]) == 0
    assert link.is_symlink() and '"coverage": 1.0' in target.read_text()


def test_a_dangling_symlink_creates_its_target(tmp_path):
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "new.json")
    assert main([LINE, "--headless", "--metrics", str(link)]) == 0
    assert link.is_symlink() and (tmp_path / "new.json").is_file()


@pytest.mark.parametrize("option", ["--metrics", "--trace", "--save-state", "--positions"])
def test_a_fifo_output_is_refused_and_left_alone(tmp_path, capsys, option):
    fifo = tmp_path / ("out.csv" if option in ("--trace", "--positions") else "out.x")
    os.mkfifo(fifo)
    assert main([LINE, "--headless", option, str(fifo)]) == 2
    assert "would replace a pipe or a device" in capsys.readouterr().err
    assert fifo.is_fifo()


def test_a_device_is_refused_even_with_force(capsys):
    assert main([LINE, "--headless", "--metrics", "/dev/null", "--force"]) == 2
    assert "would replace a pipe or a device" in capsys.readouterr().err
    assert Path("/dev/null").is_char_device()


def test_a_legal_long_name_works_and_a_too_long_one_is_refused_before_the_run(tmp_path, capsys):
    fine = tmp_path / ("m" * 250 + ".json")
    assert main([LINE, "--headless", "--metrics", str(fine)]) == 0
    assert fine.is_file()
    too_long = tmp_path / ("m" * 260 + ".json")
    assert main([LINE, "--headless", "--metrics", str(too_long)]) == 2
    assert "name is longer than" in capsys.readouterr().err


def test_a_too_long_folder_name_is_refused_before_anything_looks_it_up(tmp_path, capsys):
    """Found by the fuzz: a --frames folder named with 300 bytes crashed check_output, which
    asked whether it was a folder (ENAMETOOLONG) before measuring its name."""
    assert main([LINE, "--headless", "--frames", str(tmp_path / ("f" * 300))]) == 2
    assert "--frames name is longer than the 255 bytes allowed" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_two_options_naming_one_file_are_refused(tmp_path, capsys):
    out = tmp_path / "same.csv"
    assert main([LINE, "--headless", "--trace", str(out), "--positions", str(out)]) == 2
    assert "--trace and --positions both write it" in capsys.readouterr().err
    assert not out.exists()


def test_a_full_disk_is_one_line_and_leaves_no_temporary_file(tmp_path, monkeypatch, capsys):
    def full(*_args, **_kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    for option in ("--metrics", "--save-state"):
        assert main([LINE, "--headless", option, str(tmp_path / "out")]) == 2
        assert "cannot write it (No space left on device)" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_trace_leaves_nothing_behind(tmp_path, monkeypatch):
    from swarmshape.core.swarm import Swarm

    real_step = Swarm.step

    def interrupted(self):
        if self.step_count == 5:
            raise KeyboardInterrupt
        real_step(self)

    monkeypatch.setattr(Swarm, "step", interrupted)
    trace = tmp_path / "t.csv"
    assert (
        main([LINE, "--headless", "--trace", str(trace), "--positions", str(tmp_path / "p.csv")])
        == 130
    )
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_keeps_the_old_file_when_writing_fails(tmp_path):
    path = tmp_path / "keep.txt"
    path.write_text("precious")

    def half(tmp):
        Path(tmp).write_text("half")
        raise OSError(errno.EIO, "I/O error")

    with pytest.raises(OutputError, match="cannot write it"):
        atomic_write(path, half)
    assert path.read_text() == "precious" and list(tmp_path.iterdir()) == [path]


def test_outputs_keep_the_mode_of_the_file_they_replace_and_new_ones_follow_the_umask(tmp_path):
    """A private file replaced with --force stayed private no longer (0600 became 0644), and a
    frames folder was private whatever the umask (mkdtemp's 0700)."""
    private = tmp_path / "metrics.json"
    private.write_text("{}")
    private.chmod(0o600)
    trace = tmp_path / "trace.csv"
    trace.write_text("")
    trace.chmod(0o640)
    common = [str(SHAPES / "line.png"), "--headless", "--seed", "1", "--force"]
    frames = tmp_path / "frames"
    outputs = ["--metrics", str(private), "--trace", str(trace), "--frames", str(frames)]
    assert main([*common, *outputs]) == 0
    usual = 0o777 & ~files.umask()
    assert [path.stat().st_mode & 0o777 for path in (private, trace, frames)] == [
        0o600,
        0o640,
        usual,
    ]
    assert (next(frames.iterdir()).stat().st_mode & 0o777) == usual & 0o666


def test_temporary_names_start_with_a_short_prefix(tmp_path):
    seen = []
    atomic_write(
        tmp_path / ("x" * 200 + ".png"),
        lambda tmp: seen.append(Path(tmp).name) or Path(tmp).touch(),
    )
    assert seen[0].startswith(files.TEMP_PREFIX) and len(seen[0]) < 40


def test_a_frames_folder_output_may_not_be_a_file(tmp_path):
    path = tmp_path / "f"
    path.write_text("x")
    with pytest.raises(OutputError, match="needs a folder"):
        check_output(path, "--frames", may_replace=True, folder=True)


def test_the_crash_log_is_private_and_fresh_and_survives_a_full_temp_folder(tmp_path):
    code = (
        "import sys, tempfile\n"
        "from swarmshape import cli\n"
        "def boom(args):\n    raise RuntimeError('boom')\n"
        "cli.COMMAND_FUNCTIONS['strategies'] = boom\n"
        "sys.exit(cli.main(['strategies']))\n"
    )
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert result.returncode == 1 and len(result.stderr.strip().splitlines()) == 1
    log = Path(result.stderr.strip().rsplit(" ", 1)[1])
    assert log.parent == tmp_path and "RuntimeError: boom" in log.read_text()
    assert oct(log.stat().st_mode & 0o777) == "0o600"
    env["TMPDIR"] = str(tmp_path / "missing")
    gone = subprocess.run(
        [sys.executable, "-c", code.replace("import sys, tempfile", "import sys, tempfile\n"
         "tempfile.tempdir = '/proc/no-such-folder'")],
        capture_output=True, text=True, env=env,
    )  # fmt: skip
    lines = gone.stderr.strip().splitlines()
    assert gone.returncode == 1 and len(lines) == 1 and "RuntimeError: boom" in lines[0]


def test_a_closed_stdout_still_runs_to_the_end_and_writes_the_metrics(tmp_path):
    metrics = tmp_path / "m.json"
    command = [sys.executable, "-m", "swarmshape", LINE, "--headless", "--metrics", str(metrics)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()
    _, err = process.communicate(timeout=60)
    assert process.returncode == 0 and err == b""
    assert '"coverage": 1.0' in metrics.read_text()


def test_an_output_never_replaces_the_state_the_run_resumes(tmp_path, capsys):
    """Issue 29, case 1: a resume wrote its metrics over the state it resumed (no --force).
    Named as it is, through a symlink or a hard link, with --force or without: refused."""
    state = tmp_path / "run.state"
    assert main([LINE, "--headless", "--max-steps", "5", "--save-state", str(state)]) == 3
    saved = state.read_bytes()
    (tmp_path / "link.csv").symlink_to(state)
    (tmp_path / "hard.gif").hardlink_to(state)
    for option, out in [("--metrics", state), ("--positions", tmp_path / "link.csv"),
                        ("--record", tmp_path / "hard.gif"), ("--trace", state)]:  # fmt: skip
        for force in ([], ["--force"]):
            argv = ["--load-state", str(state), "--headless", "--max-steps", "9", option, str(out)]
            assert main([*argv, *force]) == 2
            err = capsys.readouterr().err
            assert f"{option} would replace the state this run resumes" in err, err
    assert state.read_bytes() == saved


@pytest.mark.parametrize(
    ("inputs", "output", "what"),
    [
        ([LINE], "{shape}", "its image"),
        (["{dir}/s.toml"], "{dir}/s.toml", "its scenario"),
        (["{dir}/s.toml"], "{dir}/dot.png", "an image of its scenario"),
        ([LINE, "--start", "{dir}/start.csv"], "{dir}/start.csv", "its start cells"),
        ([LINE, "--strategy", "{dir}/mine.py:Mine"], "{dir}/mine.py", "its strategy's code"),
    ],
)
def test_an_output_never_replaces_an_input_of_the_run_even_with_force(
    tmp_path, capsys, inputs, output, what
):
    shape = tmp_path / "line.png"
    shape.write_bytes(Path(LINE).read_bytes())
    (tmp_path / "dot.png").write_bytes(Path(LINE).read_bytes())
    (tmp_path / "s.toml").write_text('[[groups]]\nshape = "dot.png"\n')
    (tmp_path / "start.csv").write_text("x,y\n")
    (tmp_path / "mine.py").write_text(
        "from swarmshape.strategies.concurrent import Optimal\nclass Mine(Optimal):\n"
        "    name = 'mine'\n"
    )
    fill = {"shape": shape, "dir": tmp_path}
    argv = [arg.format(**fill) for arg in inputs]
    if argv[0] == LINE:
        argv[0] = str(shape)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    out = output.format(**fill)
    assert main([*argv, "--headless", "--metrics", out, "--force"]) == 2
    err = capsys.readouterr().err
    assert f"--metrics would replace {what}; name another file" in err, err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize("option", ["--metrics", "--trace", "--save-state", "--frames"])
def test_a_dash_is_not_taken_for_a_file_name(tmp_path, capsys, monkeypatch, option):
    """A dash means standard output to most tools; --metrics - wrote a file named "-" in the
    working folder, and the report said nothing of it."""
    monkeypatch.chdir(tmp_path)
    assert main([LINE, "--headless", option, "-"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.endswith(f"-: {option} writes a file, not standard output; name a file")
    assert list(tmp_path.iterdir()) == []
    assert main([LINE, "--headless", option, str(tmp_path / "-")]) == 0, "a file named so"
    assert [path.name for path in tmp_path.iterdir()] == ["-"]


@pytest.mark.parametrize("option", ["--metrics", "--trace", "--save-state", "--frames"])
def test_a_symlink_loop_as_an_output_is_refused_and_left_alone(tmp_path, capsys, option):
    """Issue 29, cases 2 and 12: a link to itself was replaced by the metrics, exit 0; a loop
    as --frames was a traceback."""
    (tmp_path / "self.out").symlink_to("self.out")
    (tmp_path / "a.out").symlink_to("b.out")
    (tmp_path / "b.out").symlink_to("a.out")
    for name in ("self.out", "a.out"):
        assert main([LINE, "--headless", option, str(tmp_path / name), "--force"]) == 2
        err = capsys.readouterr().err
        assert f"{name}: {option} names a symlink that leads back to itself" in err, err
    assert sorted(os.readlink(p) for p in tmp_path.iterdir()) == ["a.out", "b.out", "self.out"]


def little_room(limit: int):
    """A file size limit in a child process: writes past `limit` bytes fail as on a full disk."""

    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


@pytest.mark.parametrize("option", ["--positions", "--trace"])
def test_a_stream_on_a_full_disk_is_one_line_and_leaves_nothing(tmp_path, option):
    """Issue 29, case 3: --positions on a full disk raised again in its own clean-up (exit 1)."""
    out = tmp_path / "out.csv"
    command = [sys.executable, "-m", "swarmshape", str(SHAPES / "star.png"), "--headless",
               "--seed", "1", option, str(out)]  # fmt: skip
    done = subprocess.run(
        command, capture_output=True, text=True, preexec_fn=little_room(5000), timeout=120
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("swarmshape: error: ") and "cannot write it" in done.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_stream_that_cannot_even_flush_gives_up_in_one_line(tmp_path):
    """What a full disk did to --positions: the write failed, and closing the file to remove
    it failed again (its buffer could not be flushed), an internal error."""
    streamed = files.StreamedFile(tmp_path / "out.csv")
    streamed.handle.close()
    streamed.handle = open("/dev/full", "w")  # noqa: SIM115 (the stream closes it)
    with pytest.raises(OSError) as failure:
        streamed.handle.write("x" * 100_000)
        streamed.handle.flush()
    streamed.handle.write("more, buffered")
    error = streamed.failed(failure.value)
    assert "out.csv: cannot write it (No space left on device)" in str(error)
    assert list(tmp_path.iterdir()) == []
    streamed.discard()  # again, as a run's clean-up does: nothing to do


def test_frames_on_a_full_disk_leave_no_frame(tmp_path, monkeypatch, capsys):
    """Issue 29, case 3: --frames exited 2 but left dozens of frames. The message named the
    frame in the temporary folder, which the user never sees; it names the frames folder."""
    from PIL import Image

    real_save, saved = Image.Image.save, []

    def save(self, fp, *args, **kwargs):
        saved.append(fp)
        if len(saved) > 12:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_save(self, fp, *args, **kwargs)

    monkeypatch.setattr(Image.Image, "save", save)
    frames = tmp_path / "frames"
    assert main([LINE, "--headless", "--seed", "1", "--frames", str(frames)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.endswith(f"{frames}/frame-0000012.png: cannot write it (No space left on device)")
    assert list(tmp_path.iterdir()) == []
    frames.mkdir()
    (frames / "frame-0000000.png").write_text("an earlier run's")
    saved.clear()
    assert main([LINE, "--headless", "--seed", "1", "--frames", str(frames), "--force"]) == 2
    assert [p.name for p in tmp_path.rglob("*")] == ["frames", "frame-0000000.png"]
    assert (frames / "frame-0000000.png").read_text() == "an earlier run's"


def test_a_run_that_fails_before_its_first_step_leaves_no_temporary_file(tmp_path, capsys):
    out = [f"--trace={tmp_path / 't.csv'}", f"--positions={tmp_path / 'p.csv'}",
           f"--frames={tmp_path / 'f'}"]  # fmt: skip
    assert main([LINE, "--headless", "--strategy", "nope.py:X", *out]) == 2
    assert list(tmp_path.iterdir()) == []
    assert main([LINE, "--headless", "--trace", str(tmp_path / "t.csv"), "--positions",
                 str(tmp_path / "p.txt")]) == 2  # fmt: skip
    assert "--positions writes .npz or .csv" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("signal_number", [signal.SIGTERM, signal.SIGHUP])
def test_a_terminated_run_leaves_no_temporary_file(tmp_path, signal_number):
    """Issue 29, case 3: a run killed by SIGTERM left 22 MB of .swarmshape-* files."""
    command = [sys.executable, "-m", "swarmshape", str(SHAPES / "star.png"), "--headless",
               "--strategy", "paper", "--trace", "t.csv", "--positions", "p.csv", "--frames",
               "f", "--record", "r.gif"]  # fmt: skip
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    process = subprocess.Popen(command, cwd=tmp_path, env=env, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    while not any(p.stat().st_size > 10_000 for p in tmp_path.glob(".swarmshape-*")):
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.05)
    process.send_signal(signal_number)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 128 + signal_number, err
    assert list(tmp_path.iterdir()) == []


def test_a_nul_byte_in_an_input_name_is_one_line(tmp_path, capsys):
    """Issue 29, case 12: a scenario's or a sweep's shape path with a NUL byte in it (TOML
    allows "\\u0000") was a traceback: os.stat raises ValueError for such a name."""
    with pytest.raises(InputError, match="its name holds a NUL byte"):
        files.readable_file(Path("a\0b.png"), "an image")
    (tmp_path / "nul.toml").write_text('[[groups]]\nshape = "li\\u0000ne.png"\n')
    (tmp_path / "nul-sweep.toml").write_text(
        'shapes = ["li\\u0000ne.png"]\nstrategies = ["optimal"]\n'
    )
    assert main([str(tmp_path / "nul.toml"), "--headless"]) == 2
    assert "li\\x00ne.png: no such file (its name holds a NUL byte)" in capsys.readouterr().err
    assert main(["sweep", str(tmp_path / "nul-sweep.toml")]) == 2  # refused as a setting
    err = capsys.readouterr().err
    assert "nul-sweep.toml: shape must be a file name" in err and len(err.splitlines()) == 1


def test_a_first_ctrl_c_keeps_what_a_headless_run_reached(tmp_path):
    """Issue 29, case 18: Ctrl+C on a headless run printed "interrupted" and kept nothing."""
    command = [sys.executable, "-m", "swarmshape", str(SHAPES / "star.png"), "--headless",
               "--strategy", "paper", "--seed", "1", "--trace", "t.csv", "--metrics", "m.json",
               "--save-state", "s.state"]  # fmt: skip
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    process = subprocess.Popen(command, cwd=tmp_path, env=env, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    deadline = time.monotonic() + 60
    while not any(p.stat().st_size > 1000 for p in tmp_path.glob(".swarmshape-*")):
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 130 and "interrupted" in err, err
    reached = json.loads((tmp_path / "m.json").read_text())
    assert reached["steps"] is None and reached["steps_run"] > 0
    assert f"not formed after {reached['steps_run']:,} steps" in out
    rows = list(csv.DictReader((tmp_path / "t.csv").open()))
    assert int(rows[-1]["step"]) == reached["steps_run"]
    assert resume(tmp_path / "s.state")[1].step_count == reached["steps_run"]
    assert not list(tmp_path.glob(".swarmshape-*"))


def test_a_second_ctrl_c_interrupts_at_once():
    runner = Runner(build(configure(SHAPES / "line.png", seed=1)), max_steps=10)
    with pytest.raises(KeyboardInterrupt), stopped_by_ctrl_c(runner):
        signal.raise_signal(signal.SIGINT)
        assert runner.stopped and runner.finished and runner.swarm.step_count == 0
        signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler

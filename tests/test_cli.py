from __future__ import annotations

import contextlib
import json
import os
import subprocess

import pytest

from swarmshape.cli import main
from tests.conftest import SHAPES, python

METRIC_KEYS = {
    "shape", "strategy", "seed", "agents", "targets", "scale", "steps", "coverage", "iou",
    "entering", "uniformity", "total_distance", "overlaps", "groups",
}  # fmt: skip


def swarmshape(*args: str, fresh: bool = False) -> subprocess.CompletedProcess:
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return python("-m", "swarmshape", *args, env=env, fresh=fresh)


def test_headless_run_prints_a_summary_and_writes_metrics(tmp_path, capsys):
    out = tmp_path / "m.json"
    code = main([str(SHAPES / "line.png"), "--headless", "--seed", "4", "--metrics", str(out)])
    assert code == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("line.png: 16 robots for 16 cells") and len(lines) == 2
    assert lines[1].startswith("line.png: optimal, 16 robots, 16 targets")
    metrics = json.loads(out.read_text())
    assert set(metrics) >= METRIC_KEYS
    assert metrics["coverage"] == 1.0 and metrics["overlaps"] == 0 and metrics["seed"] == 4
    assert metrics["groups"][0]["steps"] == metrics["steps"] > 0


def test_the_summary_counts_one_robot_lost_in_the_singular(capsys):
    args = [str(SHAPES / "square.png"), "--headless", "--agents", "70", "--fail", "1@40"]
    assert main([*args, "--seed", "2"]) == 0
    assert "1 fault: 1 robot lost, 0 stalled" in capsys.readouterr().out


def test_same_seed_gives_the_same_metrics_file_byte_for_byte(tmp_path):
    files = []
    for name in ("a.json", "b.json"):
        path = tmp_path / name
        args = ["run", str(SHAPES / "two-squares.toml"), "--headless", "--seed", "21"]
        assert swarmshape(*args, "--metrics", str(path), fresh=True).returncode == 0
        files.append(path.read_bytes())
    assert files[0] == files[1]


def test_options_override_the_scenario(tmp_path):
    out = tmp_path / "m.json"
    args = [str(SHAPES / "square.png"), "--headless", "--agents", "20", "--strategy", "paper",
            "--set", "order=random"]  # fmt: skip
    assert main([*args, "--seed", "1", "--metrics", str(out)]) == 0
    metrics = json.loads(out.read_text())
    assert metrics["agents"] == 20 and metrics["targets"] <= 20 and metrics["scale"] < 1


def test_max_steps_stops_an_unfinished_run(tmp_path):
    out = tmp_path / "m.json"
    args = [str(SHAPES / "square.png"), "--headless", "--max-steps", "10", "--metrics", str(out)]
    assert main(args) == 3, "exit status 3: stopped before the shape formed"
    metrics = json.loads(out.read_text())
    assert metrics["steps"] is None and metrics["steps_run"] == 10 and metrics["coverage"] < 1


def test_version_and_help_and_strategies():
    assert swarmshape("--version").stdout.startswith("swarmshape ")
    help_text = swarmshape("run", "--help").stdout
    for option in ("--seed", "--agents", "--cells", "--threshold", "--invert", "--headless",
                   "--metrics", "--max-steps", "--set", "--strategy"):  # fmt: skip
        assert option in help_text
    assert "paper" in swarmshape("strategies").stdout


def bad_inputs(tmp_path):
    (tmp_path / "text.png").write_text("not an image")
    (tmp_path / "white.png").write_bytes((SHAPES / "line.png").read_bytes())
    (tmp_path / "bad.toml").write_text("groups = [ {shape = 'x.png'")
    (tmp_path / "typo.toml").write_text("[[groups]]\nshap = 'line.png'\n")
    return {
        "missing": ([str(tmp_path / "nope.png")], "no such file"),
        "directory": ([str(tmp_path)], "directory"),
        "not an image": ([str(tmp_path / "text.png")], "not an image"),
        "no ink": ([str(tmp_path / "white.png"), "--invert"], "no shape found"),
        "zero agents": (
            [str(SHAPES / "line.png"), "--agents", "0"],
            "--agents: must be a whole number of 1 or more",
        ),
        "malformed toml": ([str(tmp_path / "bad.toml")], "not valid TOML"),
        "unknown key": ([str(tmp_path / "typo.toml")], "unknown key 'shap'"),
        "unknown strategy": ([str(SHAPES / "line.png"), "--strategy", "nope"], "unknown strategy"),
        "no speed": (  # nan, 0 and -1 were taken as the slowest speed
            [str(SHAPES / "line.png"), "--speed", "nan"],
            "--speed: steps per frame must be a number above 0, got 'nan'",
        ),
    }


@pytest.mark.parametrize(
    "case",
    [
        "missing",
        "directory",
        "not an image",
        "no ink",
        "zero agents",
        "malformed toml",
        "unknown key",
        "unknown strategy",
        "no speed",
    ],
)
def test_bad_input_is_one_line_on_stderr_and_exit_code_2(tmp_path, case):
    args, message = bad_inputs(tmp_path)[case]
    result = swarmshape(*args, "--headless")
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("swarmshape: error: ")
    assert message in lines[0]
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("args", "shown"),
    [
        (["sweep", "{dir}/sweep.toml"], "/a\\nb: no such file"),
        (["{dir}/a\nb.png", "--headless"], "a\\nb.png: no such file"),
        ([str(SHAPES / "line.png"), "x\ny", "--headless"], "unrecognized arguments: x\\ny"),
        (["{dir}/c\x1b[31m.png", "--headless"], "c\\x1b[31m.png: no such file"),
    ],
)
def test_a_name_with_a_line_break_does_not_split_the_error_line(tmp_path, capsys, args, shown):
    """Found by the long fuzz (seed 11, case 745): a sweep file naming the shape 'a\\nb' made
    a two-line error; and an escape sequence in a name went to the terminal as it was."""
    (tmp_path / "sweep.toml").write_text('shapes = ["a\\nb"]\nstrategies = ["optimal"]\n')
    with pytest.raises(SystemExit) if "x\ny" in args else contextlib.nullcontext():
        assert main([arg.replace("{dir}", str(tmp_path)) for arg in args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and shown in err and "\x1b" not in err


def test_start_packed_runs_self_assembly_from_a_block_against_the_seeds(tmp_path, capsys):
    out = tmp_path / "m.json"
    args = [str(SHAPES / "small-square.png"), "--headless", "--strategy", "self-assembly"]
    code = main([*args, "--start", "packed", "--seed", "2", "--metrics", str(out)])
    assert code == 0
    metrics = json.loads(out.read_text())
    assert metrics["coverage"] == 1.0 and metrics["overlaps"] == 0


# a name too long for any file system was an internal error (the fuzz, reading a state's config)
@pytest.mark.parametrize("word", ["pakced", "a" * 300])
def test_an_unknown_start_word_is_one_line_on_stderr(word):
    result = swarmshape(str(SHAPES / "line.png"), "--headless", "--start", word)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "--start: must be packed, scatter or a CSV file" in lines[0]

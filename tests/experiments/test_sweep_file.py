"""Reading sweep files: every key checked before any run, and runs made only as needed."""

from __future__ import annotations

import os
import threading
import tracemalloc
from pathlib import Path

import pytest

from swarmshape.errors import InputError
from swarmshape.experiments.sweep import read_sweep, run_one, sweep
from tests.conftest import SHAPES

LINE = f"shapes = ['{SHAPES / 'line.png'}']\nstrategies = ['optimal']\n"


def sweep_file(tmp_path, text):
    path = tmp_path / "sweep.toml"
    path.write_text(text)
    return path


def peak_bytes(call):
    tracemalloc.start()
    try:
        result = call()
        return result, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_a_sweep_at_the_cap_is_counted_without_making_its_runs(tmp_path):
    path = sweep_file(tmp_path, LINE.replace("'optimal'", "'optimal', 'greedy'") + "seeds = 50000")
    runs, peak = peak_bytes(lambda: read_sweep(path))
    assert len(runs) == 100_000
    assert peak < 5_000_000
    first = next(iter(runs))
    assert first["seed"] == 0 and first["strategy"] == "optimal"


def test_a_sweep_over_the_cap_is_refused_saying_how_many_runs_it_asks_for(tmp_path):
    text = LINE.replace("'optimal'", "'optimal', 'greedy'") + "agents = [10, 20, 30]\n"
    path = sweep_file(tmp_path, text + "seeds = 100000")
    with pytest.raises(InputError, match=r"asks for 600,000 runs, more than the 100,000") as error:
        peak_bytes(lambda: read_sweep(path))
    assert str(error.value).startswith(f"{path}: ")
    path.write_text(LINE + "seeds = 1000000000000000000")
    with pytest.raises(InputError, match="1,000,000,000,000,000,000 runs"):
        read_sweep(path)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("agents = 'x'", "agents must be a whole number (0: one per cell), or a list of them; "
         "got 'x'"),
        ("agents = [10, 2.5]", "agents must be a whole number (0: one per cell), or a list of "
         "them; got 2.5"),
        ("agents = -1", "agents must be a whole number (0: one per cell)"),
        ("agents = true", "agents must be a whole number"),
        ("agents = []", "agents is an empty list; give it at least one value"),
        ("agents = [10, 10]", "agents lists 10 twice"),
        ("agents = {a = 1}", "agents must be a whole number"),
        ("max_speed = 'fast'", "max_speed must be a number from 0.001 to 1, or a list of them; "
         "got 'fast'"),
        ("max_speed = 3", "max_speed must be a number from 0.001 to 1, or a list of them; got 3"),
        ("max_speed = 0.25\nmax_accel = 0.5", "max_accel must be at most max_speed (0.25), "
         "got 0.5"),
        ("cells = 0", "cells must be a whole number of 1 or more"),
        ("msg_loss = [0, 1]", "msg_loss must be a number from 0 up to (not including) 1, or a "
         "list of them; got 1"),
        ("distance_noise = 'some'", "distance_noise must be a number from 0 to 1"),
        ("sense_radius = 0.5", "sense_radius must be a number from 1 to 16"),
        ("arena = [30, 0]", "arena must be two whole numbers of 1 or more"),
        ("speed_variation = true", "speed_variation must be a number"),
        ("curve_every = -2", "curve_every must be a whole number of at least 1, or a list of "
         "them; got -2"),
        ("curve_every = 0", "curve_every must be a whole number of at least 1"),
        ("order = 'random'", "unknown key 'order' (order is an option of paper: write "
         "options.order)"),
        ("options.order = 'nope'", "order is an option of paper, not of optimal"),
        ("strategies = ['paper']\noptions.order = 'nope'", "order must be one of outward, "
         "left-to-right, random, got 'nope'"),
        ("strategies = ['paper']\noptions.order = [3]", "order must be one of outward"),
        ("options = 3", "options must be a table: options.NAME = [values]"),
        ("max_steps = -1", "max_steps must be a whole number of 0 or more"),
        ("max_steps = 1.5", "max_steps must be a whole number of 0 or more"),
        ("seeds = [-1]", "seeds must be a count of at least 1, or a list of seeds from 0 to "
         "2**63 - 1; got -1"),
        ("seeds = [1, 2**63]", "seeds must be a count"),
        ("seeds = true", "seeds must be a count"),
        ("seeds = 0", "seeds must be a count of at least 1"),
        ("seeds = []", "seeds is an empty list"),
        ("seeds = [3, 3]", "seeds lists 3 twice"),
    ],
)  # fmt: skip
def test_every_value_is_checked_before_any_run_naming_the_file_and_the_key(
    tmp_path, extra, message
):
    base = LINE.replace("strategies = ['optimal']\n", "") if "strategies" in extra else LINE
    path = sweep_file(tmp_path, base + extra.replace("2**63", str(2**63)))
    with pytest.raises(InputError) as error:
        read_sweep(path)
    assert str(error.value).startswith(f"{path}: ")
    assert message in str(error.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("shapes = [1]\nstrategies = ['optimal']", "shapes must be a file name, or a list of "
         "them; got 1"),
        ("shapes = ['nope.png']\nstrategies = ['optimal']", "nope.png: no such file"),
        ("shapes = []\nstrategies = ['optimal']", "shapes is an empty list"),
        (LINE.replace("'optimal'", "''"), "strategies must be a strategy name"),
        (LINE.replace("'optimal'", "['optimal']"), "strategies must be a strategy name, or a "
         "list of them; got ['optimal']"),
        (LINE + "agents = 2000000", "more than the 1,000,000 swarmshape simulates"),
    ],
)  # fmt: skip
def test_shapes_and_strategies_are_checked_too(tmp_path, text, message):
    path = sweep_file(tmp_path, text)
    with pytest.raises(InputError) as error:
        read_sweep(path)
    assert str(error.value).startswith(f"{path}: ")
    assert message in str(error.value)


def test_a_folder_is_not_a_sweep_file(tmp_path):
    with pytest.raises(InputError, match=r"is a directory, expected a sweep \.toml file"):
        read_sweep(tmp_path)


def test_good_values_make_every_combination_once_per_seed(tmp_path):
    text = LINE + "agents = [0, 20]\nseeds = [7, 3]\nmax_speed = [0.5, 1]\ncurve_every = 5\n"
    runs = list(read_sweep(sweep_file(tmp_path, text)))
    assert len(runs) == 8
    assert runs[0] == {
        "agents": 0,
        "cells": None,
        "curve_every": 5,
        "max_speed": 0.5,
        "max_steps": 500_000,
        "shape": str(SHAPES / "line.png"),
        "strategy": "optimal",
        "seed": 7,
    }
    assert [(r["agents"], r["max_speed"], r["seed"]) for r in runs[:4]] == [
        (0, 0.5, 7),
        (0, 0.5, 3),
        (0, 1, 7),
        (0, 1, 3),
    ]


def test_noise_keys_reach_each_run(tmp_path):
    text = LINE.replace("optimal", "local-swap") + "msg_loss = [0, 0.5]\nmax_steps = 30\n"
    path = sweep_file(tmp_path, text)
    rows = [run_one(run, path.parent) for run in read_sweep(path)]
    assert [row["config.msg_loss"] for row in rows] == [0, 0.5]
    assert rows[0]["messages_lost"] == 0 < rows[1]["messages_lost"]


def test_a_pipe_or_a_device_is_refused_not_read(tmp_path):
    """Found by the fuzz: a pipe hung the sweep, and /dev/zero filled the memory."""
    pipe = tmp_path / "pipe.toml"
    os.mkfifo(pipe)
    outcome = []
    thread = threading.Thread(target=lambda: outcome.append(_refusal(pipe)), daemon=True)
    thread.start()
    thread.join(5)
    assert outcome and "pipe.toml: is not a regular file" in outcome[0]
    assert "is not a regular file" in _refusal(Path("/dev/zero"))


def _refusal(path: Path) -> str:
    try:
        read_sweep(path)
    except InputError as error:
        return str(error)
    return "read"


def test_a_sweep_file_of_a_too_long_name_is_not_there(tmp_path):
    """Found by the fuzz: looking the name up raised ENAMETOOLONG, an internal error."""
    with pytest.raises(InputError, match="no such sweep file"):
        read_sweep(tmp_path / ("s" * 300 + ".toml"))


def test_a_sweep_file_nested_too_deeply_is_one_clear_error(tmp_path):
    path = sweep_file(tmp_path, LINE + f"agents = {'[' * 3000}{']' * 3000}\n")
    with pytest.raises(InputError, match=r"nested too deeply to be a sweep \.toml file"):
        read_sweep(path)


def test_a_sweep_file_with_a_number_longer_than_int_reads_is_one_clear_error(tmp_path):
    """Found by the fuzz (seed 38): tomllib reads integers with int(), whose ValueError past
    4,300 digits is not a TOMLDecodeError, and was an internal error."""
    path = sweep_file(tmp_path, LINE + f"seeds = {'9' * 5000}\n")
    with pytest.raises(InputError, match="holds a number of more than 4,300 digits"):
        read_sweep(path)


def test_more_seeds_than_a_range_can_count_are_refused_as_too_many_runs(tmp_path):
    """Found by the fuzz: seeds = 10**30 was an OverflowError."""
    path = sweep_file(tmp_path, LINE + f"seeds = {10**30}")
    with pytest.raises(InputError, match=f"asks for {10**30:,} runs, more than the 100,000"):
        read_sweep(path)


@pytest.mark.parametrize("address", ["", "nope://x:1", "tcp://a:b"])
def test_a_malformed_dask_address_is_one_clear_error(tmp_path, address):
    """Found by the fuzz: Dask's ValueError was an internal error, and an empty address ran
    the sweep on local processes without a word."""
    runs = read_sweep(sweep_file(tmp_path, LINE))
    with pytest.raises(InputError, match="is not the address of a Dask scheduler"):
        sweep(runs, tmp_path / "out.csv", tmp_path, dask=address)
    assert not (tmp_path / "out.csv").exists()

"""The results file of a sweep: resumed safely, never garbled, never someone else's file."""

from __future__ import annotations

import csv
import io
import json
import resource
import signal
import subprocess
import sys
import threading

import pytest

from swarmshape.errors import InputError
from swarmshape.experiments.results import open_results, read_rows
from swarmshape.experiments.sweep import read_sweep, sweep
from swarmshape.io.bitmap import ShapeWarning
from tests.conftest import SHAPES

TINY = f"""
shapes = ["{SHAPES / "line.png"}"]
strategies = ["optimal", "greedy"]
agents = [0, 20]
seeds = 2
"""


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


@pytest.fixture
def swept(tiny, tmp_path):
    """The tiny sweep's eight rows, finished, and their file's bytes."""
    out = tmp_path / "tiny.csv"
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=2) == 8
    return out, out.read_bytes()


def without_times(rows):
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]


def test_a_second_sweep_on_the_same_file_is_refused_while_the_first_runs(tiny, tmp_path):
    out, runs = tmp_path / "out.csv", read_sweep(tiny)
    started, release = threading.Event(), threading.Event()

    def wait_after_the_first_row(done, total):
        started.set()
        release.wait(30)

    first = threading.Thread(
        target=sweep, args=(runs, out, tiny.parent), kwargs={"workers": 1,
        "progress": wait_after_the_first_row},
    )  # fmt: skip
    first.start()
    try:
        assert started.wait(30)
        with pytest.raises(InputError, match="another sweep is writing to it"):
            sweep(runs, out, tiny.parent, workers=1)
    finally:
        release.set()
        first.join(60)
    rows = read_rows(out)
    assert len(rows) == 8 and len({row["run"] for row in rows}) == 8
    assert sweep(runs, out, tiny.parent, workers=1) == 0  # the lock went with the first sweep
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_two_links_to_one_results_file_share_its_lock(tmp_path):
    """Noticed writing the fuzz's rule for which lock a sweep may touch: the lock was named
    after the link, so two sweeps writing one file through two links each held their own."""
    for name in ("a.csv", "b.csv"):
        (tmp_path / name).symlink_to(tmp_path / "results.csv")
    with (
        open_results(tmp_path / "a.csv", ["config.seed"]),
        pytest.raises(InputError, match="another sweep is writing to it"),
        open_results(tmp_path / "b.csv", ["config.seed"]),
    ):
        pass
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


@pytest.mark.parametrize("cut", [1, 20, 300], ids=["newline", "in the curve", "in the run key"])
def test_a_row_cut_short_is_dropped_and_run_again(tiny, swept, cut):
    out, whole = swept
    out.write_bytes(whole[:-cut])
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=1) == 1
    assert without_times(read_rows(out)) == without_times(read_rows_of(whole, out))
    assert out.read_bytes().count(b"\n") == 9


def read_rows_of(data, out):
    copy = out.with_name("copy.csv")
    copy.write_bytes(data)
    return read_rows(copy)


def test_a_full_disk_leaves_whole_rows_and_the_sweep_resumes(tiny, tmp_path):
    """The disk fills up (a file size limit) after a few rows: the sweep says so, exit 2,
    keeps whole rows only; run again with room, it finishes the rest."""
    out = tmp_path / "tiny.csv"
    command = [sys.executable, "-m", "swarmshape", "sweep", str(tiny), "--workers", "1"]

    def little_room():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (2500, 2500))

    full = subprocess.run(
        command, capture_output=True, text=True, preexec_fn=little_room, timeout=120
    )
    assert full.returncode == 2, full.stderr
    assert "cannot write to it (File too large); what it holds is unharmed" in full.stderr
    assert len(full.stderr.strip().splitlines()) == 1
    written = out.read_bytes()
    assert written.endswith(b"\n") and 2 <= written.count(b"\n") < 9
    again = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    rows = read_rows(out)
    assert len(rows) == 8 and {row["coverage"] for row in rows} == {"1.0"}


def test_a_sweep_that_gained_a_setting_does_not_resume_into_the_old_file(tiny, swept):
    out, whole = swept
    tiny.write_text(TINY + "max_speed = 0.5\n")
    with pytest.raises(InputError) as error:
        sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    assert str(error.value) == (
        f"{out}: its rows come from a sweep with other settings (this sweep adds max_speed); "
        "write to a new --out, or add --force to start it over"
    )
    assert out.read_bytes() == whole
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=2, force=True) == 8
    rows = read_rows(out)
    assert len(rows) == 8 and {row["config.max_speed"] for row in rows} == {"0.5"}


@pytest.mark.parametrize(
    "text",
    [b"x,y\n1,2\n", b"run,x\n1,2\n", b"\x89PNG\r\n\x1a\n\x00\xff", b"not a csv at all"],
    ids=["other csv", "a run column", "binary", "text"],
)
def test_someone_elses_file_is_never_appended_to(tiny, tmp_path, text):
    out = tmp_path / "theirs.csv"
    out.write_bytes(text)
    with pytest.raises(
        InputError, match=r"theirs\.csv: not a swarmshape sweep CSV; choose another"
    ):
        sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    assert out.read_bytes() == text
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=2, force=True) == 8
    assert len(read_rows(out)) == 8


@pytest.mark.parametrize("glue", [b"", b"\n"], ids=["glued to the next", "then a newline"])
def test_a_damaged_row_in_the_middle_is_refused_not_dropped(tiny, swept, glue):
    out, whole = swept
    lines = whole.splitlines(keepends=True)
    lines[3] = lines[3][:50] + glue  # cut inside its run key, as old resumes left them
    out.write_bytes(b"".join(lines))
    columns = len(lines[0].decode().split(","))
    damaged = rf"line 4 is damaged \(\d+ fields for {columns} columns\)"
    with pytest.raises(InputError, match=damaged):
        sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    assert out.read_bytes() == b"".join(lines)


def test_a_missing_folder_is_refused_before_any_run(tiny, tmp_path):
    def no_run_may_finish(done, total):
        raise AssertionError("a run finished")

    with pytest.raises(InputError, match="--out cannot write there"):
        sweep(read_sweep(tiny), tmp_path / "nowhere" / "out.csv", tiny.parent, workers=1,
              progress=no_run_may_finish)  # fmt: skip


def test_rows_are_sorted_with_numbers_as_numbers(tiny, tmp_path):
    tiny.write_text(TINY.replace("agents = [0, 20]", "agents = [135, 45, 9]"))
    out = tmp_path / "out.csv"
    with pytest.warns(ShapeWarning, match="will wait outside it"):
        sweep(read_sweep(tiny), out, tiny.parent, workers=2)
    keys = [(r["config.strategy"], r["config.agents"], r["config.seed"]) for r in read_rows(out)]
    assert keys == [
        (strategy, agents, seed)
        for strategy in ("greedy", "optimal")
        for agents in ("9", "45", "135")
        for seed in ("0", "1")
    ]


def test_repeated_rows_are_kept_once_and_a_file_in_order_is_left_alone(tiny, swept):
    out, whole = swept
    lines = whole.splitlines(keepends=True)
    out.write_bytes(b"".join(lines + lines[3:5]))
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=1) == 0
    assert out.read_bytes() == whole
    before = out.stat().st_mtime_ns
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=1) == 0
    assert out.stat().st_mtime_ns == before


def test_a_long_coverage_curve_reads_back(tiny, swept):
    out, _ = swept
    curve = read_rows(out)[0]["coverage_curve"]
    long_curve = json.dumps([0.5] * 40_000)  # 200,000 characters, over csv's default limit
    out.write_text(out.read_text().replace(curve, long_curve, 1))
    assert json.loads(read_rows(out)[0]["coverage_curve"]) == [0.5] * 40_000
    assert sweep(read_sweep(tiny), out, tiny.parent, workers=1) == 0


@pytest.mark.parametrize(
    ("before", "after"),
    [('""seed"": 1', '""seed"": 7'), ('""strategy"": ""optimal""', '""strategy"": ""random""')],
    ids=["seed", "strategy"],
)
def test_a_row_whose_run_key_disagrees_with_its_settings_is_damaged(tiny, swept, before, after):
    """Issue 29, case 4: a row whose run key was changed was kept as a foreign run on resume
    (9 rows for an 8-run sweep); its settings columns still said which run it was."""
    out, whole = swept
    lines = whole.splitlines(keepends=True)
    line = next(i for i, text in enumerate(lines) if before.encode() in text)
    lines[line] = lines[line].replace(before.encode(), after.encode(), 1)
    out.write_bytes(b"".join(lines))
    with pytest.raises(InputError) as error:
        sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    message = f"{out}: line {line + 1} is damaged (its run key does not match its settings)"
    assert str(error.value).startswith(message)
    assert out.read_bytes() == b"".join(lines)


@pytest.mark.parametrize("key", ["[" * 5000 + "]" * 5000, '{"seed": ' + "9" * 5000 + "}"])
def test_a_run_key_json_cannot_read_is_damaged_not_a_crash(tiny, swept, key):
    """Found by the fuzz: a run key nested 5,000 deep was a RecursionError; a number of more
    digits than int() reads, a ValueError that is no JSONDecodeError."""
    out, whole = swept
    lines = whole.decode().splitlines(keepends=True)
    fields = next(csv.reader([lines[2]]))
    fields[0] = key
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerow(fields)
    lines[2] = buffer.getvalue()
    out.write_text("".join(lines))
    with pytest.raises(InputError, match="line 3 is damaged"):
        sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    with pytest.raises(InputError, match="line 3 is damaged"):
        read_rows(out)


def test_a_file_with_runs_of_another_sweep_is_not_resumed_into(tiny, swept):
    """Issue 29, case 4: a sweep whose --out was another sweep's file, with the same keys but
    one value changed, merged both silently."""
    from swarmshape.experiments.sweep import run_key

    out, whole = swept
    runs = [run_key(config) for config in read_sweep(tiny)]
    other = [key.replace('"seed": 1', '"seed": 2') for key in runs]
    settings = [f"config.{name}" for name in sorted(json.loads(runs[0]))]
    with open_results(out, settings, runs=runs[:6] + runs):  # a sweep of more seeds: fine
        pass
    with pytest.raises(InputError) as error, open_results(out, settings, runs=other):
        pass
    assert str(error.value) == (
        f"{out}: line 3 is a run this sweep does not have (seed 1); write to a new --out, or "
        "add --force to start it over"
    )
    with open_results(out, settings, runs=other, force=True) as results:
        assert results.done == set()
    assert out.read_bytes() == whole

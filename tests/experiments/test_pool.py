"""A sweep's worker processes: no more than there are runs, gone with their sweep, and a
sweep stopped with Ctrl+C or kill -9 leaves a valid results file."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from swarmshape.experiments.results import read_rows
from swarmshape.experiments.sweep import read_sweep, sweep
from tests.conftest import SHAPES

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="reads processes from /proc")

SLOW = f"""
shapes = ["{SHAPES / "star.png"}"]
strategies = {{strategies}}
seeds = 2
max_steps = 1000000
"""
"""The paper's method on the star: minutes per run, long enough to be stopped."""


def children(pid: int) -> set[int]:
    """Living processes whose parent is `pid`."""
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] != "Z" and int(fields[1]) == pid:
            found.add(int(stat.parent.name))
    return found


def alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def wait_for(condition, seconds: float):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if result := condition():
            return result
        time.sleep(0.05)
    return condition()


def _as_in_a_terminal() -> None:
    """Ctrl+C as a terminal delivers it: a suite started in the background (``nohup ... &``)
    ignores SIGINT, and a child inherits that, so the sweep never heard it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start_sweep(tmp_path, strategies: str) -> tuple[subprocess.Popen, Path]:
    """A sweep in its own process group; its output goes to files (pipes would be held open
    by any worker left behind)."""
    path = tmp_path / "slow.toml"
    path.write_text(SLOW.format(strategies=strategies))
    command = [sys.executable, "-m", "swarmshape", "sweep", str(path), "--workers", "2"]
    with (tmp_path / "stdout").open("w") as stdout, (tmp_path / "stderr").open("w") as stderr:
        process = subprocess.Popen(
            command,
            stdout=stdout,
            stderr=stderr,
            start_new_session=True,
            preexec_fn=_as_in_a_terminal,
        )
    return process, path.with_suffix(".csv")


def end(process: subprocess.Popen, workers: set[int]) -> None:
    """Whatever the test found, leave no process of it behind."""
    for pid in {process.pid} | workers:
        if alive(pid):
            os.kill(pid, signal.SIGKILL)
    process.wait()


def test_workers_die_with_a_sweep_killed_with_kill_9(tmp_path):
    process, _ = start_sweep(tmp_path, '["paper"]')
    workers = set()
    try:
        workers = wait_for(lambda: children(process.pid) if len(children(process.pid)) >= 2
                           else None, 20)  # fmt: skip
        assert workers, "the sweep started no workers"
        time.sleep(0.5)  # under way
        os.kill(process.pid, signal.SIGKILL)
        process.wait(10)
        assert wait_for(lambda: not any(alive(pid) for pid in workers), 5), "workers live on"
    finally:
        end(process, workers)


def test_ctrl_c_keeps_finished_rows_and_exits_130_without_a_traceback(tmp_path):
    process, out = start_sweep(tmp_path, '["optimal", "paper"]')
    workers = set()
    try:
        assert wait_for(lambda: out.exists() and out.read_text().count("\n") == 3, 60)
        workers = children(process.pid)
        os.killpg(process.pid, signal.SIGINT)  # as a terminal does: the sweep and its workers
        process.wait(10)
        stderr = (tmp_path / "stderr").read_text()
        assert process.returncode == 130, stderr
        assert "Traceback" not in stderr
        assert stderr.strip().splitlines() == [
            f"swarmshape: interrupted; finished runs are kept in {out}: run the same command "
            "to go on"
        ]
        rows = read_rows(out)
        assert [(row["strategy"], row["coverage"]) for row in rows] == [("optimal", "1.0")] * 2
        assert wait_for(lambda: not any(alive(pid) for pid in workers), 5), "workers live on"
    finally:
        end(process, workers)


def test_never_more_workers_than_runs_left(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(f"shapes = ['{SHAPES / 'line.png'}']\nstrategies = ['optimal']\nseeds = 3\n")
    out = tmp_path / "tiny.csv"
    sweep(read_sweep(path), out, tmp_path, workers=1)
    lines = out.read_text().splitlines(keepends=True)
    out.write_text("".join(lines[:3]))  # one run left
    counted = []

    def count_workers(done, total):
        counted.append(len(multiprocessing.active_children()))

    ran = sweep(read_sweep(path), out, tmp_path, workers=64, progress=count_workers)
    assert ran == 1 and counted == [1]

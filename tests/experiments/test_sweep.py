"""Sweeps on local processes and on a Dask cluster, resuming, and plots."""

from __future__ import annotations

import shutil

import pytest
from PIL import Image

from swarmshape.cli import main
from swarmshape.errors import InputError
from swarmshape.experiments.plot import plot_results
from swarmshape.experiments.results import read_rows
from swarmshape.experiments.sweep import read_sweep, sweep
from tests.conftest import SHAPES

TINY = f"""
shapes = ["{SHAPES / "line.png"}"]
strategies = ["optimal", "greedy"]
agents = [0, 20]
seeds = 2
"""


def without_times(rows):
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def test_eight_runs_are_the_same_on_processes_and_on_a_dask_cluster(tiny, tmp_path):
    from dask.distributed import LocalCluster

    runs = read_sweep(tiny)
    assert len(runs) == 8
    assert sweep(runs, tmp_path / "pool.csv", tiny.parent, workers=2) == 8
    with LocalCluster(n_workers=2, processes=False, dashboard_address=None) as cluster:
        assert sweep(runs, tmp_path / "dask.csv", tiny.parent, dask=cluster.scheduler_address) == 8
    pool, dask = read_rows(tmp_path / "pool.csv"), read_rows(tmp_path / "dask.csv")
    assert len(pool) == 8 and without_times(pool) == without_times(dask)
    assert {row["coverage"] for row in pool} == {"1.0"}


def test_a_killed_sweep_resumes_without_redoing_finished_rows(tiny, tmp_path):
    out = tmp_path / "out.csv"
    runs = read_sweep(tiny)
    sweep(runs, out, tiny.parent, workers=1)
    rows = read_rows(out)
    # as if killed after five runs: the header and five rows were on disk
    lines = out.read_text().splitlines(keepends=True)
    out.write_text("".join(lines[:6]))
    kept = {row["run"]: row["wall_time"] for row in read_rows(out)}
    assert sweep(runs, out, tiny.parent, workers=1) == 3
    again = read_rows(out)
    assert without_times(again) == without_times(rows)
    assert all(row["wall_time"] == kept[row["run"]] for row in again if row["run"] in kept)


def test_a_sweep_never_resumes_into_another_sweeps_results(tiny, tmp_path):
    """Issue 29, case 4, through `sweep` itself (the fuzz, seed 46): its results file only
    knew which runs were the sweep's when told, and the sweep never told it, so a sweep whose
    --out held another sweep's rows added its own to them, exit 0."""
    out = tmp_path / "out.csv"
    sweep(read_sweep(tiny), out, tiny.parent, workers=1)
    theirs = out.read_bytes()
    other = tmp_path / "other.toml"
    other.write_text(TINY.replace("seeds = 2", "seeds = 2\nmax_steps = 900"))
    with pytest.raises(InputError, match="is a run this sweep does not have"):
        sweep(read_sweep(other), out, other.parent, workers=1)
    assert out.read_bytes() == theirs
    assert sweep(read_sweep(other), out, other.parent, workers=1, force=True) == 8
    assert {row["config.max_steps"] for row in read_rows(out)} == {"900"}


def test_the_command_line_sweeps_and_plots(tiny, tmp_path, capsys):
    assert main(["sweep", str(tiny), "--workers", "2"]) == 0
    out = capsys.readouterr().out
    assert "8 runs done now" in out
    assert f"the results are in {tmp_path / 'tiny.csv'}" in out
    assert main(["sweep", str(tiny)]) == 0
    assert "0 runs done now, 8 were there already" in capsys.readouterr().out
    paths = plot_results(tmp_path / "tiny.csv", tmp_path / "plots", ("png", "svg"))
    assert sorted(p.name for p in paths) == [
        "coverage.png",
        "coverage.svg",
        "steps.png",
        "steps.svg",
    ]
    with Image.open(tmp_path / "plots" / "coverage.png") as image:
        assert image.size[0] > 400


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("strategies = ['optimal']", "needs shapes"),
        (TINY + "speed = 3\n", "unknown key 'speed'"),
        (TINY.replace("seeds = 2", "seeds = 'two'"), "seeds must be"),
        ("shapes = [", "not valid TOML"),
        # checked by shape, cells and robots alone, these ended a sweep after the runs before
        (TINY + "arena = [[40, 24], [3, 3]]\n", "outside the 3x3 arena"),
        (
            TINY.replace('"greedy"', '"self-assembly"').replace('"optimal", ', "")
            + "options.patience = [1, 99999999999999999999]\n",
            "at most 9,223,372,",
        ),
    ],
)
def test_bad_sweep_files_say_what_is_wrong(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_sweep(path)


def test_plots_are_not_overwritten_without_force(tiny, tmp_path, capsys):
    assert main(["sweep", str(tiny), "--workers", "1"]) == 0
    plots = tmp_path / "plots"
    assert main(["plot", str(tmp_path / "tiny.csv"), "--out", str(plots)]) == 0
    before = (plots / "steps.png").stat().st_mtime_ns
    assert main(["plot", str(tmp_path / "tiny.csv"), "--out", str(plots)]) == 2
    assert "add --force" in capsys.readouterr().err
    assert (plots / "steps.png").stat().st_mtime_ns == before
    assert main(["plot", str(tmp_path / "tiny.csv"), "--out", str(plots), "--force"]) == 0


def test_a_sweep_varies_faults_and_reports_the_slowest_recovery(tmp_path):
    path = tmp_path / "faults.toml"
    path.write_text(
        f'shapes = ["{SHAPES / "line.png"}"]\nstrategies = ["optimal"]\nagents = 20\n'
        'fail = ["0.2@40", "3@40"]\nstall = "1@20"\nfailure_rate = [0, 0.001]\nseeds = 1\n'
    )
    runs = read_sweep(path)
    assert len(runs) == 4
    assert sweep(runs, tmp_path / "faults.csv", path.parent, workers=1) == 4
    rows = read_rows(tmp_path / "faults.csv")
    assert {row["config.fail"] for row in rows} == {"0.2@40", "3@40"}
    assert all(int(row["robots_lost"]) >= 3 and row["overlaps"] == "0" for row in rows)
    assert all(row["recovery_steps"] != "" for row in rows)


@pytest.mark.parametrize(
    ("out", "what"),
    [
        ("sweep.toml", "the sweep file"),
        ("shape.png", "its image"),
        ("two.toml", "its scenario"),
        ("dot.png", "an image of its scenario"),
    ],
)
def test_a_sweep_never_writes_its_results_over_a_file_it_reads(tmp_path, capsys, out, what):
    """The fuzz (seed 40) named a sweep's own shape as its --out, with --force, and the sweep
    wrote its rows over the picture; the sweep file itself went the same way."""
    shutil.copy(SHAPES / "line.png", tmp_path / "shape.png")
    shutil.copy(SHAPES / "line.png", tmp_path / "dot.png")
    (tmp_path / "two.toml").write_text('[[groups]]\nshape = "dot.png"\n')
    (tmp_path / "sweep.toml").write_text(
        'shapes = ["shape.png", "two.toml"]\nstrategies = ["optimal"]\nmax_steps = 5\n'
    )
    before = {path.name: path.read_bytes() for path in tmp_path.iterdir()}
    args = ["sweep", str(tmp_path / "sweep.toml"), "--workers", "1", "--force"]
    assert main([*args, "--out", str(tmp_path / out)]) == 2
    assert f"--out would replace {what}" in capsys.readouterr().err
    assert {path.name: path.read_bytes() for path in tmp_path.iterdir()} == before

"""Plots of a sweep's results: one line per setting, and one clear error for a bad file."""

from __future__ import annotations

import csv
import errno
import io
import json
import os
import re
import threading

import matplotlib
import pytest

from swarmshape.cli import main
from swarmshape.experiments.plot import MARKERS, draw_plots, plot_results, read_runs
from swarmshape.experiments.sweep import read_sweep, sweep
from tests.conftest import SHAPES

TINY = f"""
shapes = ["{SHAPES / "line.png"}"]
strategies = ["optimal", "greedy"]
agents = [0, 20]
seeds = 2
"""


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """The tiny sweep's results: line.png (16 cells) with 16 and 20 robots, two seeds each."""
    folder = tmp_path_factory.mktemp("results")
    (folder / "tiny.toml").write_text(TINY)
    sweep(read_sweep(folder / "tiny.toml"), folder / "tiny.csv", folder, workers=2)
    return folder / "tiny.csv"


def rows_of(path):
    with path.open(newline="") as handle:
        return list(csv.reader(handle))


def csv_text(rows):
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def changed(results, column, value):
    """The results with `column` of the first row set to `value`."""
    rows = rows_of(results)
    rows[1][rows[0].index(column)] = value
    return csv_text(rows)


def without(results, column):
    rows = rows_of(results)
    index = rows[0].index(column)
    return csv_text([row[:index] + row[index + 1 :] for row in rows])


def legend(path):
    """The legend texts of an SVG drawn with text kept as text."""
    return re.findall(r"<text[^>]*>([^<]*)</text>", path.read_text())


BAD = {
    "empty": (lambda r: "", "bad.csv: not a swarmshape sweep CSV (it is empty)"),
    "header only": (lambda r: r.read_text().splitlines(keepends=True)[0],
                    "bad.csv: no sweep results in it"),
    "missing column": (lambda r: without(r, "steps"),
                       "bad.csv: lacks the column steps, which the plots need"),
    "steps not a number": (lambda r: changed(r, "steps", "many"),
                           "bad.csv: row 1: steps is not a whole number of at least 0, got 'many'"),
    "steps below 0": (lambda r: changed(r, "steps", "-5"),
                      "row 1: steps is not a whole number of at least 0, got '-5'"),
    "steps past the run": (lambda r: changed(r, "steps", "99999"),
                           "row 1: steps 99999 is past steps_run"),
    "agents not whole": (lambda r: changed(r, "agents", "2.5"),
                         "bad.csv: row 1: agents is not a whole number of at least 1, got '2.5'"),
    "curve_every zero": (lambda r: changed(r, "curve_every", "0"),
                         "bad.csv: row 1: curve_every is not a whole number of at least 1"),
    "steps not finite": (lambda r: changed(r, "steps", "nan"), "row 1: steps is not a whole"),
    "bad JSON curve": (lambda r: changed(r, "coverage_curve", "[0.1,"),
                       "bad.csv: row 1: coverage_curve is not a list of numbers"),
    "curve nested too deep": (lambda r: changed(r, "coverage_curve", "[" * 100_000),
                              "row 1: coverage_curve is not a list of numbers"),
    "curve of text": (lambda r: changed(r, "coverage_curve", '["a"]'),
                      "row 1: coverage_curve is not a list of numbers"),
    "curve past 1": (lambda r: changed(r, "coverage_curve", "[0, 1.5]"),
                     "row 1: coverage_curve is not a list of numbers from 0 to 1"),
    "a run twice": (lambda r: r.read_text() + r.read_text().splitlines(keepends=True)[1],
                    "bad.csv: row 9 is the run of row 1 again"),
    "curve too short": (lambda r: changed(r, "coverage_curve", "[0.5]"),
                        "row 1: coverage_curve has 1 values, where steps_run"),
    "cut short": (lambda r: r.read_text()[:-20], "bad.csv: line 9 is cut short"),
    "binary": (lambda r: b"\x89PNG\r\n\x1a\n\x00\xff\xfe", "bad.csv: not a swarmshape sweep CSV"),
    "another CSV": (lambda r: "x,y\n1,2\n", "bad.csv: not a swarmshape sweep CSV"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_results_file_is_one_clear_line(results, tmp_path, capsys, case):
    make, message = BAD[case]
    bad = tmp_path / "bad.csv"
    content = make(results)
    bad.write_bytes(content if isinstance(content, bytes) else content.encode())
    assert main(["plot", str(bad), "--out", str(tmp_path / "plots")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "plots").exists()


@pytest.mark.parametrize(
    ("target", "message"),
    [("nope.csv", "nope.csv: no such file"), (".", "is a directory, expected a sweep's results")],
)
def test_a_missing_file_or_a_folder_is_one_clear_line(tmp_path, capsys, target, message):
    assert main(["plot", str(tmp_path / target), "--out", str(tmp_path / "plots")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_a_pipe_is_refused_at_once_instead_of_hanging(tmp_path, capsys):
    """Found by the fuzz: plot waited for a writer to the pipe, for good."""
    pipe = tmp_path / "results.csv"
    os.mkfifo(pipe)
    outcome = []
    command = ["plot", str(pipe), "--out", str(tmp_path / "plots")]
    thread = threading.Thread(target=lambda: outcome.append(main(command)), daemon=True)
    thread.start()
    thread.join(5)
    assert outcome == [2]
    assert "results.csv: is not a regular file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


@pytest.mark.parametrize("out", ["f" * 300, "f" * 300 + "/plots"])
def test_plots_into_a_folder_of_a_too_long_name_are_one_clear_line(results, tmp_path, capsys, out):
    """Found by the fuzz: asking whether the plots existed there raised ENAMETOOLONG."""
    assert main(["plot", str(results), "--out", str(tmp_path / out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot write the plots there (File name too long)" in err[0], err


def test_plots_into_a_file_are_one_clear_line(results, tmp_path, capsys):
    (tmp_path / "taken").write_text("mine")
    assert main(["plot", str(results), "--out", str(tmp_path / "taken")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "taken: cannot make the folder for the plots" in err[0], err


def test_plots_into_a_dash_are_one_clear_line(results, tmp_path, capsys, monkeypatch):
    """--out - made a folder named "-" (a dash is standard output to most tools)."""
    monkeypatch.chdir(tmp_path)
    assert main(["plot", str(results), "--out", "-"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "swarmshape: error: -: --out writes a folder, not standard output; name a folder"
    ]
    assert list(tmp_path.iterdir()) == []


def test_plots_that_cannot_all_be_written_leave_the_old_ones(
    results, tmp_path, capsys, monkeypatch
):
    """On a full disk the coverage plot was replaced and the steps plot was not: a pair that
    no longer belonged together. The plots are written together or not at all."""
    from swarmshape.experiments import plot

    for name in ("coverage.png", "steps.png"):
        (tmp_path / name).write_text(f"the old {name}")
    saved = plot._save

    def full_disk(figure, form, path):
        if figure is figures["steps"]:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        saved(figure, form, path)

    drawn = plot.draw_plots
    figures = {}
    monkeypatch.setattr(plot, "draw_plots", lambda runs: figures.update(drawn(runs)) or figures)
    monkeypatch.setattr(plot, "_save", full_disk)
    assert main(["plot", str(results), "--out", str(tmp_path), "--force"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.endswith("steps.png: cannot write it (No space left on device)"), line
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == {
        "coverage.png": b"the old coverage.png",
        "steps.png": b"the old steps.png",
    }


def looks(axes) -> list[tuple]:
    """Colour, line style and marker of each line drawn for a setting (not error bar caps)."""
    return [
        (line.get_color(), line.get_linestyle(), line.get_marker())
        for line in axes.get_lines()
        if line.get_marker() in MARKERS
    ]


def drawn(path, name):
    """A plot's figure, drawn, its panels that hold lines, and its legends' texts."""
    figure = draw_plots(read_runs(path))[name]
    figure.canvas.draw()
    panels = [axes for axes in figure.axes if axes.get_lines()]
    texts = [text.get_text() for legend in figure.legends for text in legend.get_texts()]
    return figure, panels, texts


def assert_legends_outside_the_panels(figure) -> None:
    assert figure.legends
    for legend in figure.legends:
        for axes in figure.axes:
            assert not legend.get_window_extent().overlaps(axes.get_window_extent())


def test_coverage_tells_every_strategy_and_robot_count_apart(results, tmp_path, monkeypatch):
    figure, (panel,) = drawn(results, "coverage")[:2]
    assert len(looks(panel)) == 4 and len(set(looks(panel))) == 4
    assert len({colour for colour, _, _ in looks(panel)}) == 2, "a colour per strategy"
    assert len({look[1:] for look in looks(panel)}) == 2, "a style per robot count"
    assert_legends_outside_the_panels(figure)
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")
    plot_results(results, tmp_path, ("svg",))
    texts = legend(tmp_path / "coverage.svg")
    assert {"strategy", "greedy", "optimal", "robots", "16 robots", "20 robots"} <= set(texts)
    assert "Coverage over time, mean over seeds (2 runs each)" in texts
    assert {"greedy", "optimal"} <= set(legend(tmp_path / "steps.svg"))


def test_several_shapes_get_a_panel_each_and_single_points_differ_in_marker(tmp_path):
    """With one robot per cell each shape has one robot count, so in steps.png every setting
    is a single point: colour alone, or line style, could not tell them apart."""
    sweep_file = tmp_path / "two.toml"
    sweep_file.write_text(
        TINY.replace('"]', f'", "{SHAPES / "small-square.png"}"]', 1)
        .replace("agents = [0, 20]", "agents = 0\nmax_speed = [0.5, 1.0]")
        .replace('["optimal", "greedy"]', '"optimal"')
    )
    sweep(read_sweep(sweep_file), tmp_path / "two.csv", tmp_path, workers=2)
    figure, panels, texts = drawn(tmp_path / "two.csv", "coverage")
    assert [axes.get_title() for axes in panels] == ["line.png, 16 robots",
                                                     "small-square.png, 36 robots"]  # fmt: skip
    assert {"max_speed 0.5", "max_speed 1.0"} <= set(texts)
    assert all(len(set(looks(axes))) == 2 for axes in panels)
    assert_legends_outside_the_panels(figure)
    figure, panels, texts = drawn(tmp_path / "two.csv", "steps")
    assert [axes.get_title() for axes in panels] == ["line.png", "small-square.png"]
    for axes in panels:
        assert len(looks(axes)) == 2 and len({marker for *_, marker in looks(axes)}) == 2
    assert {"max_speed 0.5", "max_speed 1.0"} <= set(texts)
    assert_legends_outside_the_panels(figure)


def test_a_dollar_in_a_setting_is_drawn_as_it_is(results, tmp_path, monkeypatch):
    """A value with "$" signs, e.g. a strategy named $\\frac{1}{0$, was read as a formula by
    matplotlib, whose ParseSyntaxException was an internal error (and left an empty plots
    folder behind)."""
    rows = rows_of(results)
    column = rows[0].index("config.strategy")
    for row in rows[1:]:
        row[column] = row[column].replace("optimal", r"$\frac{1}{0$")
        row[0] = row[0].replace('"optimal"', json.dumps(r"$\frac{1}{0$"))  # its run key agrees
    (tmp_path / "dollar.csv").write_text(csv_text(rows))
    monkeypatch.setitem(matplotlib.rcParams, "svg.fonttype", "none")
    plot_results(tmp_path / "dollar.csv", tmp_path / "plots", ("svg",))
    labels = legend(tmp_path / "plots" / "coverage.svg")
    assert r"$\frac{1}{0$" in labels

"""Plots of a sweep's results (matplotlib, the ``plot`` extra): coverage over time, and steps
to form versus robot count with error bars over seeds.

Runs are averaged only over their seeds: a line is one setting (strategy, robots, and any
other value the sweep varied). Each shape gets its own panel; in every panel a strategy has
one colour, and each of the other values (robots, and anything else the sweep varied) one
line style and one marker, so every line differs from every other in colour or in style
and marker, even where a setting is a single point. The legend, outside the panels, names
the colours and the styles apart.
"""

from __future__ import annotations

import functools
import json
import math
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarmshape.errors import InputError
from swarmshape.experiments.results import read_rows
from swarmshape.io.files import atomic_writes, not_standard_output

PLOTS = ("coverage", "steps")
NEEDED = (
    "config.shape",
    "config.strategy",
    "agents",
    "steps",
    "steps_run",
    "curve_every",
    "coverage_curve",
)
"""Columns the plots read (besides the other ``config.`` ones, which tell settings apart)."""
LINES = ("-", "--", ":", "-.")
MARKERS = ("o", "s", "^", "D", "v", "P", "X")
"""Line styles and markers, paired in turn: 28 styles before a pair repeats (4 and 7 share no
factor)."""
SYMLOG_FROM = 10
"""Steps from which the coverage plot's axis is logarithmic, when runs go on ten times
longer: the paper's method takes thousands of steps where the others take a hundred."""
PANEL = (4.2, 3.4)
"""Inches of one panel; the legend adds its own width on the right."""

Setting = tuple[tuple[str, str], ...]
"""A run's ``config.`` values but its seed and robot count, as (name, value) pairs."""


@dataclass(frozen=True)
class Run:
    """What the plots need of one row, checked."""

    setting: Setting
    robots: int
    steps: float | None
    """Steps until formed; None if it never was."""
    every: int
    sampled: np.ndarray
    """The steps at which coverage was sampled: every `every`, and the last step."""
    coverage: np.ndarray


def plot_results(
    results: Path, out_dir: Path, formats: tuple[str, ...] = ("png",), *, force: bool = False
) -> list[Path]:
    """Write coverage.FORMAT and steps.FORMAT beside each other; return their paths.

    Existing plots are replaced only with `force`; everything is checked before anything is
    drawn."""
    not_standard_output(out_dir, "--out", "a folder")
    targets = [out_dir / f"{name}.{form}" for name in PLOTS for form in formats]
    try:
        taken = [path for path in targets if path.exists()]
    except OSError as error:  # a name too long, a file where a folder should be
        raise InputError(f"{out_dir}: cannot write the plots there ({error.strerror})") from None
    if taken and not force:
        raise InputError(f"{taken[0]}: exists; add --force to overwrite it")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("plot needs the plot extra: pip install 'swarmshape[plot]'") from None
    runs = read_runs(results)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        message = f"{out_dir}: cannot make the folder for the plots ({error.strerror})"
        raise InputError(message) from None
    figures = draw_plots(runs)
    writes = {
        out_dir / f"{name}.{form}": functools.partial(_save, figure, form)
        for name, figure in figures.items()
        for form in formats
    }
    try:
        atomic_writes(list(writes.items()))  # all of them, or none (a full disk)
    finally:
        for figure in figures.values():
            plt.close(figure)
    return list(writes)


def _save(figure: Any, form: str, path: str) -> None:
    figure.savefig(path, format=form, dpi=120)


def draw_plots(runs: list[Run]) -> dict[str, Any]:
    """The figures by name (`PLOTS`), drawn but not saved."""
    return {"coverage": _coverage_over_time(runs), "steps": _steps_per_robots(runs)}


def read_runs(path: Path) -> list[Run]:
    """Every row of a results file, checked; a bad one is one error naming its row."""
    rows = read_rows(path)
    if not rows:
        raise InputError(f"{path}: no sweep results in it (write some with swarmshape sweep)")
    missing = [column for column in NEEDED if column not in rows[0]]
    if missing:
        raise InputError(f"{path}: lacks the column {missing[0]}, which the plots need")
    runs = []
    seen: dict[tuple, int] = {}
    for number, row in enumerate(rows, start=1):
        try:
            runs.append(_run(row))
        except ValueError as error:
            raise InputError(f"{path}: row {number}: {error}") from None
        # a run counted twice would weigh twice in its setting's mean
        run = tuple((name, value) for name, value in row.items() if name.startswith("config."))
        if run in seen:
            raise InputError(f"{path}: row {number} is the run of row {seen[run]} again")
        seen[run] = number
    return runs


def _run(row: dict[str, str]) -> Run:
    every = _whole(row, "curve_every", 1)
    steps_run = _whole(row, "steps_run", 0)
    try:
        coverage = json.loads(row["coverage_curve"])
    except (ValueError, RecursionError):  # deep nesting exhausts the parser's stack (the fuzz)
        coverage = None
    numbers = isinstance(coverage, list) and all(map(_finite, coverage))
    if not numbers or not coverage or not all(0 <= value <= 1 for value in coverage):
        raise ValueError("coverage_curve is not a list of numbers from 0 to 1")
    samples = steps_run // every + 1 + (steps_run % every > 0)
    if len(coverage) != samples:
        raise ValueError(
            f"coverage_curve has {len(coverage)} values, where steps_run {steps_run} and "
            f"curve_every {every} make {samples}"
        )
    setting = tuple(
        (name.removeprefix("config."), value)
        for name, value in row.items()
        if name.startswith("config.") and name not in ("config.seed", "config.agents")
    )
    return Run(
        setting=setting,
        robots=_whole(row, "agents", 1),
        steps=None if row["steps"] == "" else _formed_at(row, steps_run),
        every=every,
        sampled=np.minimum(np.arange(len(coverage)) * every, steps_run),
        coverage=np.array(coverage, dtype=float),
    )


def _whole(row: dict[str, str], column: str, least: int) -> int:
    value = row[column]
    if not value.isdecimal() or int(value) < least:
        raise ValueError(f"{column} is not a whole number of at least {least}, got {value!r}")
    return int(value)


def _formed_at(row: dict[str, str], steps_run: int) -> int:
    """The step the run formed at: one of those it ran."""
    steps = _whole(row, "steps", 0)
    if steps > steps_run:
        raise ValueError(f"steps {steps} is past steps_run {steps_run}")
    return steps


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _varied(settings: list[Setting]) -> list[str]:
    """The settings' names whose values differ between them, but the shape and the strategy
    (which have their panels and colours)."""
    values = [dict(setting) for setting in settings]
    names = [name for name, _ in settings[0] if name not in ("shape", "strategy")]
    return [name for name in names if len({v[name] for v in values}) > 1]


def _text(value: str) -> str:
    return value.replace("$", r"\$")  # a "$" starts no formula here


class Legend:
    """Colours by strategy and line styles with markers by everything else, handed out in a
    fixed order so that every panel agrees."""

    def __init__(self, strategies: list[str], styles: list[tuple]) -> None:
        self.strategies = sorted(set(strategies))
        self.styles = sorted(set(styles))

    def look(self, strategy: str, style: tuple) -> dict[str, Any]:
        index = self.styles.index(style)
        return {
            "color": f"C{self.strategies.index(strategy) % 10}",
            "linestyle": LINES[index % len(LINES)],
            "marker": MARKERS[index % len(MARKERS)],
            "markerfacecolor": "none",  # hollow: a point under another still shows
        }

    def draw(self, figure, name: str, label) -> None:
        """Two legends outside the panels, on the right: the strategies' colours, then what
        each style stands for (`label` names a style; none if there is only one)."""
        from matplotlib.lines import Line2D

        colours = [
            Line2D([], [], color=f"C{i % 10}", linewidth=2.5) for i in range(len(self.strategies))
        ]
        first = figure.legend(
            colours,
            [_text(s) for s in self.strategies],
            title="strategy",
            loc="outside right upper",
            fontsize="small",
        )
        if len(self.styles) < 2:
            return
        looks = [self.look(self.strategies[0], style) | {"color": "0.25"} for style in self.styles]
        figure.legend(
            [Line2D([], [], **look) for look in looks],
            [label(style) for style in self.styles],
            title=name,
            loc="outside right lower",
            fontsize="small",
        )
        figure.add_artist(first)


def _panels(shapes: dict[str, str], title: str):
    """A figure with one panel per shape, sharing their y axis, titled by the shape's name
    and what `shapes` says of it."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    columns = min(len(shapes), 3)
    rows = math.ceil(len(shapes) / columns)
    figure, grid = plt.subplots(
        rows,
        columns,
        figsize=(PANEL[0] * columns + 2.4, PANEL[1] * rows + 0.5),
        sharey=True,
        squeeze=False,
        layout="constrained",
    )
    for spare in grid.flat[len(shapes) :]:
        spare.set_axis_off()
    figure.suptitle(title, x=0.02, ha="left")  # centred, a long title ran under the legends
    panels = dict(zip(sorted(shapes), grid.flat, strict=False))
    for shape, axes in panels.items():
        axes.set_title(_text(f"{Path(shape).name}{shapes[shape]}"), fontsize="medium")
        axes.xaxis.set_major_locator(MaxNLocator(integer=True))
        axes.grid(alpha=0.3)
    return figure, panels


def _style_label(names: list[str], robots: bool):
    """How a style is named in the legend: the varied values, and the robot count if the
    style includes it."""

    def label(style: tuple) -> str:
        values = style[:-1] if robots else style
        parts = [f"{name} {value}" for name, value in zip(names, values, strict=True)]
        parts += [f"{style[-1]} robots"] if robots else []
        return _text(", ".join(parts))

    return label


def _coverage_over_time(runs: list[Run]):
    """Mean coverage of each setting and robot count over its seeds; a run that finished
    early stays at its last value. Where each shape has one robot count (one robot per
    cell, say), the count goes in its panel's title instead of the legend."""
    groups: dict[tuple[Setting, int], list[Run]] = defaultdict(list)
    for run in runs:
        groups[(run.setting, run.robots)].append(run)
    settings = sorted({setting for setting, _ in groups})
    varied = _varied(settings)
    counts_of: dict[str, set[int]] = defaultdict(set)
    for setting, robots in groups:
        counts_of[dict(setting)["shape"]].add(robots)
    by_robots = any(len(counts) > 1 for counts in counts_of.values())

    def style(setting: Setting, robots: int) -> tuple:
        values = tuple(dict(setting)[name] for name in varied)
        return (*values, robots) if by_robots else values

    legend = Legend(
        [dict(setting)["strategy"] for setting, _ in groups], [style(*key) for key in groups]
    )
    sizes = sorted({len(group) for group in groups.values()})
    each = f"{sizes[0]}" if len(sizes) == 1 else f"{sizes[0]} to {sizes[-1]}"
    notes = {
        shape: "" if by_robots else f", {next(iter(counts))} robots"
        for shape, counts in counts_of.items()
    }
    figure, panels = _panels(notes, f"Coverage over time, mean over seeds ({each} runs each)")
    for (setting, robots), group in sorted(groups.items()):
        values = dict(setting)
        end = max(int(run.sampled[-1]) for run in group)
        steps = np.union1d(np.arange(0, end, min(run.every for run in group)), [end])
        mean = np.mean([np.interp(steps, run.sampled, run.coverage) for run in group], axis=0)
        look = legend.look(values["strategy"], style(setting, robots))
        panels[values["shape"]].plot(steps, mean, markevery=0.1, **look)
    longest = max(int(run.sampled[-1]) for run in runs)
    for axes in panels.values():
        if longest > 10 * SYMLOG_FROM:  # runs of very different lengths: log beyond it
            axes.set_xscale("symlog", linthresh=SYMLOG_FROM)
        axes.set_xlim(left=0)
        axes.set_xlabel("step")
        axes.set_ylim(0, 1.02)
    next(iter(panels.values())).set_ylabel("coverage")
    names = [*varied, "robots"] if by_robots else varied
    legend.draw(figure, ", ".join(names), _style_label(varied, robots=by_robots))
    return figure


def _steps_per_robots(runs: list[Run]):
    """Steps until formed against robot count, mean and standard deviation over seeds."""
    from matplotlib.ticker import LogFormatter

    steps: dict[Setting, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for run in runs:
        if run.steps is not None:
            steps[run.setting][run.robots].append(run.steps)
    settings = sorted(steps) or sorted({run.setting for run in runs})
    varied = _varied(settings)

    def style(setting: Setting) -> tuple:
        return tuple(dict(setting)[name] for name in varied)

    legend = Legend([dict(s)["strategy"] for s in settings], [style(s) for s in settings])
    figure, panels = _panels(
        dict.fromkeys((dict(setting)["shape"] for setting in settings), ""),
        "Steps to form the shape, mean and spread over seeds",
    )
    counts: dict[str, set[int]] = defaultdict(set)
    for setting in sorted(steps):
        values = dict(setting)
        robots = sorted(steps[setting])
        means = [np.mean(steps[setting][count]) for count in robots]
        spread = [np.std(steps[setting][count]) for count in robots]
        look = legend.look(values["strategy"], style(setting))
        panels[values["shape"]].errorbar(robots, means, yerr=spread, capsize=3, **look)
        counts[values["shape"]].update(robots)
    for shape, axes in panels.items():
        if 0 < len(counts[shape]) <= 8:  # few robot counts: name them, and no others
            axes.set_xticks(sorted(counts[shape]))
    for axes in panels.values():
        axes.set_yscale("log")
        axes.yaxis.set_major_formatter(LogFormatter())  # 100, not 10^2
        axes.yaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False, minor_thresholds=(1, 1)))
        axes.set_xlabel("robots")
    next(iter(panels.values())).set_ylabel("steps to form")
    if steps:
        legend.draw(figure, ", ".join(varied), _style_label(varied, robots=False))
    return figure

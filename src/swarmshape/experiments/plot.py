"""Plots of a sweep's results (matplotlib, the ``plot`` extra): coverage over time, and steps
to form versus robot count with error bars over seeds.

Runs are averaged only over their seeds: a line is one setting (strategy, robots, and any
other value the sweep varied, such as the shape), labelled with what tells it apart.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarmshape.errors import InputError
from swarmshape.experiments.results import read_rows
from swarmshape.io.files import atomic_write

PLOTS = ("coverage", "steps")
NEEDED = ("config.strategy", "agents", "steps", "steps_run", "curve_every", "coverage_curve")
"""Columns the plots read (besides the other ``config.`` ones, which tell settings apart)."""
STYLES = ("-", "--", ":", "-.")
"""Line styles of one strategy's settings; each strategy has its colour."""

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
    written = []
    for name, draw in zip(PLOTS, (_coverage_over_time, _steps_per_robots), strict=True):
        figure, axes = plt.subplots(figsize=(7, 4.2), layout="constrained")
        draw(axes, runs)
        for form in formats:
            path = out_dir / f"{name}.{form}"
            save = figure.savefig
            atomic_write(path, lambda tmp, form=form, save=save: save(tmp, format=form, dpi=120))
            written.append(path)
        plt.close(figure)
    return written


def read_runs(path: Path) -> list[Run]:
    """Every row of a results file, checked; a bad one is one error naming its row."""
    rows = read_rows(path)
    if not rows:
        raise InputError(f"{path}: no sweep results in it (write some with swarmshape sweep)")
    missing = [column for column in NEEDED if column not in rows[0]]
    if missing:
        raise InputError(f"{path}: lacks the column {missing[0]}, which the plots need")
    runs = []
    for number, row in enumerate(rows, start=1):
        try:
            runs.append(_run(row))
        except ValueError as error:
            raise InputError(f"{path}: row {number}: {error}") from None
    return runs


def _run(row: dict[str, str]) -> Run:
    every = _whole(row, "curve_every", 1)
    steps_run = _whole(row, "steps_run", 0)
    try:
        coverage = json.loads(row["coverage_curve"])
    except json.JSONDecodeError:
        coverage = None
    numbers = isinstance(coverage, list) and all(map(_finite, coverage))
    if not numbers or not coverage:
        raise ValueError("coverage_curve is not a list of numbers")
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
        steps=None if row["steps"] == "" else _number(row, "steps"),
        every=every,
        sampled=np.minimum(np.arange(len(coverage)) * every, steps_run),
        coverage=np.array(coverage, dtype=float),
    )


def _whole(row: dict[str, str], column: str, least: int) -> int:
    value = row[column]
    if not value.isdecimal() or int(value) < least:
        raise ValueError(f"{column} is not a whole number of at least {least}, got {value!r}")
    return int(value)


def _number(row: dict[str, str], column: str) -> float:
    try:
        number = float(row[column])
    except ValueError:
        number = math.nan
    if not math.isfinite(number):
        raise ValueError(f"{column} is not a number, got {row[column]!r}")
    return number


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _labels(settings: list[Setting]) -> list[str]:
    """Each setting named by its shape if several, its strategy, and any other value that
    differs between the settings."""
    differ = {name for name, _ in settings[0] if len({dict(s)[name] for s in settings}) > 1}
    labels = []
    for setting in settings:
        values = dict(setting)
        parts = [Path(values["shape"]).name] if "shape" in differ else []
        parts.append(values["strategy"])
        parts += [f"{name} {value}" for name, value in setting
                  if name in differ - {"shape", "strategy"}]  # fmt: skip
        labels.append(", ".join(parts).replace("$", r"\$"))  # a "$" starts no formula here
    return labels


def _styles(settings: list[Setting]) -> list[dict[str, str]]:
    """A colour per strategy, and a line style per setting within it."""
    strategies = sorted({dict(setting)["strategy"] for setting in settings})
    seen: dict[str, int] = defaultdict(int)
    styles = []
    for setting in settings:
        strategy = dict(setting)["strategy"]
        colour = f"C{strategies.index(strategy) % 10}"
        styles.append({"color": colour, "linestyle": STYLES[seen[strategy] % len(STYLES)]})
        seen[strategy] += 1
    return styles


def _coverage_over_time(axes, runs: list[Run]) -> None:
    """Mean coverage of each setting and robot count over its seeds; a run that finished
    early stays at its last value."""
    groups: dict[tuple[Setting, int], list[Run]] = defaultdict(list)
    for run in runs:
        groups[(run.setting, run.robots)].append(run)
    keys = sorted(groups)
    settings = [setting for setting, _ in keys]
    for key, label, style in zip(keys, _labels(settings), _styles(settings), strict=True):
        group = groups[key]
        end = max(int(run.sampled[-1]) for run in group)
        steps = np.union1d(np.arange(0, end, min(run.every for run in group)), [end])
        mean = np.mean([np.interp(steps, run.sampled, run.coverage) for run in group], axis=0)
        axes.plot(steps, mean, label=f"{label}, {key[1]} robots ({len(group)} runs)", **style)
    axes.set_xscale("symlog", linthresh=100)
    axes.set_xlabel("step")
    axes.set_ylabel("coverage")
    axes.set_ylim(0, 1.02)
    axes.legend(fontsize="small")
    axes.set_title("Coverage over time, mean over seeds")


def _steps_per_robots(axes, runs: list[Run]) -> None:
    """Steps until formed against robot count, mean and standard deviation over seeds."""
    steps: dict[Setting, dict[int, list[float]]] = defaultdict(lambda: defaultdict(list))
    for run in runs:
        if run.steps is not None:
            steps[run.setting][run.robots].append(run.steps)
    settings = sorted(steps)
    labels = _labels(settings) if settings else []
    for setting, label, style in zip(settings, labels, _styles(settings), strict=True):
        robots = sorted(steps[setting])
        means = [np.mean(steps[setting][count]) for count in robots]
        spread = [np.std(steps[setting][count]) for count in robots]
        axes.errorbar(robots, means, yerr=spread, marker="o", capsize=3, label=label, **style)
    axes.set_yscale("log")
    axes.set_xlabel("robots")
    axes.set_ylabel("steps to form")
    if settings:
        axes.legend(fontsize="small")
    axes.set_title("Steps to form the shape, mean and spread over seeds")

"""Plots of a sweep's results (matplotlib, the ``plot`` extra): coverage over time per
strategy, and steps to form versus agent count with error bars over seeds."""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from swarmshape.errors import InputError
from swarmshape.experiments.results import read_rows
from swarmshape.io.files import atomic_write

PLOTS = ("coverage", "steps")


def plot_results(
    results: Path, out_dir: Path, formats: tuple[str, ...] = ("png",), *, force: bool = False
) -> list[Path]:
    """Write coverage.FORMAT and steps.FORMAT beside each other; return their paths.

    Existing plots are replaced only with `force`, checked before anything is drawn."""
    targets = [out_dir / f"{name}.{form}" for name in PLOTS for form in formats]
    taken = [path for path in targets if path.exists()]
    if taken and not force:
        raise InputError(f"{taken[0]}: exists; add --force to overwrite it")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("plot needs the plot extra: pip install 'swarmshape[plot]'") from None
    rows = read_rows(results)
    if not rows:
        raise InputError(f"{results}: no sweep results in it (write some with swarmshape sweep)")
    if "coverage_curve" not in rows[0]:
        raise InputError(f"{results}: not a swarmshape sweep CSV")
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name, draw in zip(PLOTS, (_coverage_over_time, _steps_per_agents), strict=True):
        figure, axes = plt.subplots(figsize=(7, 4.2), layout="constrained")
        draw(axes, rows)
        for form in formats:
            path = out_dir / f"{name}.{form}"
            save = figure.savefig
            atomic_write(path, lambda tmp, form=form, save=save: save(tmp, format=form, dpi=120))
            written.append(path)
        plt.close(figure)
    return written


def _coverage_over_time(axes, rows: list[dict[str, str]]) -> None:
    """Mean coverage of each strategy's runs; a finished run stays at its last value."""
    curves: dict[str, list[np.ndarray]] = defaultdict(list)
    every: dict[str, int] = {}
    for row in rows:
        curves[row["strategy"]].append(np.array(json.loads(row["coverage_curve"])))
        every[row["strategy"]] = int(row["curve_every"])
    for strategy, runs in sorted(curves.items()):
        length = max(len(run) for run in runs)
        padded = np.array([np.pad(run, (0, length - len(run)), mode="edge") for run in runs])
        steps = np.arange(length) * every[strategy]
        axes.plot(steps, padded.mean(axis=0), label=f"{strategy} ({len(runs)} runs)")
    axes.set_xscale("symlog", linthresh=100)
    axes.set_xlabel("step")
    axes.set_ylabel("coverage")
    axes.set_ylim(0, 1.02)
    axes.legend()
    axes.set_title("Coverage over time, mean over runs")


def _steps_per_agents(axes, rows: list[dict[str, str]]) -> None:
    """Steps until formed against agent count, mean and standard deviation over seeds."""
    steps: dict[tuple[str, int], list[float]] = defaultdict(list)
    for row in rows:
        if row["steps"]:
            steps[(row["strategy"], int(row["agents"]))].append(float(row["steps"]))
    for strategy in sorted({s for s, _ in steps}):
        agents = sorted(a for s, a in steps if s == strategy)
        means = [np.mean(steps[(strategy, a)]) for a in agents]
        spread = [np.std(steps[(strategy, a)]) for a in agents]
        axes.errorbar(agents, means, yerr=spread, marker="o", capsize=3, label=strategy)
    axes.set_yscale("log")
    axes.set_xlabel("agents")
    axes.set_ylabel("steps to form")
    axes.legend()
    axes.set_title("Steps to form the shape, mean and spread over seeds")

"""Fault figures: how each strategy heals a 1,000-cell disc. Not part of the test suite.

For each strategy the disc is formed (with one robot per cell, and with a quarter more as
spares); then 20 % of the robots that form it are removed, at random or as one block (a band
across one side holding a fifth of the cells), and the run goes on until every reachable cell is
filled again, or, too few robots left to fill them, until every survivor rests on the shape
(``--on-loss keep``, the default: the disc keeps its size) or the disc is re-formed smaller and
filled (``--on-loss rescale``). Separately, the disc is formed from scratch under a steady
failure rate. Writes ``docs/faults-keep.json`` (or ``docs/faults-rescale.json``),
``docs/fault-coverage.png`` (coverage through a fault; needs the plot extra) and
``docs/faults-healing.png`` (a disc healing, drawn offscreen); the pictures heal with spares,
which never leave the disc short of robots, so the mode changes nothing in them.

    .venv/bin/python scripts/faults.py [--strategies optimal greedy random paper] [--cells 1000]
        [--on-loss keep|rescale] [--out docs/faults-keep.json] [--no-pictures | --pictures-only]
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench import disc, world_of
from swarmshape.core.faults import Faults
from swarmshape.core.metrics import coverage, run_metrics
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import SETTLED
from swarmshape.core.swarm import Params, Swarm
from swarmshape.strategies import create

DOCS = Path(__file__).resolve().parent.parent / "docs"
SHARE = 0.2
SPARES = 0.25
SEED = 1
LIMIT = {"optimal": 20_000, "greedy": 20_000, "random": 40_000, "paper": 400_000}
RATES = {"optimal": 1e-4, "greedy": 1e-4, "random": 1e-4, "paper": 1e-6}
"""Failure rate per robot per step during formation: paper's formation takes ~500 times as
many steps, so it gets a rate ~100 times lower (and the concurrent rate is reported for it
too when asked with --paper-at-concurrent-rate)."""


def form(
    strategy: str, cells: int, spares: bool, rate: float = 0.0, on_loss: str = "keep"
) -> Swarm:
    agents = cells + (round(SPARES * cells) if spares else 0)
    world, params = world_of(disc(cells), agents), Params(on_loss=on_loss)
    swarm = Swarm(world, create(strategy), SEED, params, faults=Faults((), rate))
    while not swarm.complete and swarm.step_count < LIMIT[strategy]:
        swarm.step()
    return swarm


def fork(swarm: Swarm) -> Swarm:
    """An independent copy of a run, through its saved state."""
    saved = Snapshot(copy.deepcopy(swarm.snapshot()))
    return Swarm.restored(saved, create(swarm.plugin.name))


def strike(swarm: Swarm, kind: str) -> np.ndarray:
    """Remove a fifth of the robots that form the shape: at random, or a band on one side."""
    on_shape = np.flatnonzero(swarm.state == SETTLED)
    count = round(SHARE * len(on_shape))
    if kind == "random":
        return np.sort(swarm.rng.choice(on_shape, count, replace=False))
    targets = swarm.world.targets
    edge = np.sort(targets[:, 0])[count - 1]  # the band x <= edge holds a fifth of the cells
    low, high = targets.min(axis=0), targets.max(axis=0)
    inside = (swarm.cell[:, 0] <= edge) & (swarm.cell >= low).all(1) & (swarm.cell <= high).all(1)
    return np.flatnonzero(inside & swarm.present)


def heal(swarm: Swarm, strategy: str, kind: str) -> tuple[dict, list[float]]:
    robots = strike(swarm, kind)
    started, curve = swarm.step_count, [coverage(swarm)]
    swarm.fail(robots, "remove", label=kind)
    curve.append(coverage(swarm))
    limit = started + LIMIT[strategy]
    while not swarm.complete and swarm.step_count < limit:
        swarm.step()
        curve.append(coverage(swarm))
    entry = swarm.faults.log[-1]
    metrics = run_metrics(swarm)
    return {
        "robots_removed": len(robots),
        "coverage_after_fault": entry["coverage_after"],
        "recovery_steps": entry["recovery_steps"],
        "final_coverage": metrics["coverage"],
        "final_scale": metrics["scale"],
        "targets_after": metrics["targets"],
        "cells_left_open": metrics["cells_left_open"],
        "overlaps": metrics["overlaps"],
    }, curve


def under_rate(strategy: str, cells: int, spares: bool, rate: float, on_loss: str) -> dict:
    swarm = form(strategy, cells, spares, rate, on_loss)
    metrics = run_metrics(swarm)
    recovered = [f["recovery_steps"] for f in metrics["faults"]]
    return {
        "rate": rate,
        "steps": metrics["steps"],
        "steps_run": metrics["steps_run"],
        "robots_lost": metrics["robots_lost"],
        "final_coverage": metrics["coverage"],
        "final_scale": metrics["scale"],
        "targets_after": metrics["targets"],
        "cells_left_open": metrics["cells_left_open"],
        "overlaps": metrics["overlaps"],
        "failure_events": len(recovered),
        "unrecovered_events": recovered.count(None),
    }


def healing_picture(path: Path) -> None:
    """Four frames of the disc under `optimal` with spares: formed, a block just removed,
    refilling, healed."""
    from swarmshape.ui.render import Renderer, frame

    swarm = form("optimal", 1000, spares=True)
    shots = [("formed", frame(swarm, (360, 260)))]
    swarm.fail(strike(swarm, "block"), "remove", label="block")
    renderer = Renderer(swarm.world)
    shots.append((f"step {swarm.step_count}: 20% removed", frame(swarm, (360, 260), renderer)))
    fault_step = swarm.step_count
    while swarm.step_count < fault_step + 110:
        swarm.step()
    shots.append((f"+{swarm.step_count - fault_step} steps", frame(swarm, (360, 260), renderer)))
    while not swarm.complete:
        swarm.step()
    shots.append(
        (f"healed, +{swarm.step_count - fault_step} steps", frame(swarm, (360, 260), renderer))
    )
    from PIL import Image, ImageDraw

    strip = Image.new("RGB", (4 * 360 + 3 * 6, 260 + 24), (255, 255, 255))
    draw = ImageDraw.Draw(strip)
    for index, (label, pixels) in enumerate(shots):
        strip.paste(Image.fromarray(pixels), (index * 366, 24))
        draw.text((index * 366 + 6, 6), label, fill=(30, 30, 30))
    strip.save(path)


def coverage_plot(curves: dict[str, list[float]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(7, 3.6), dpi=110)
    for strategy, curve in curves.items():
        steps = np.arange(len(curve)) - 1
        axes.plot(np.maximum(steps, 0.5), curve, label=strategy)
    axes.set_xscale("log")
    axes.set_xlabel("steps since 20 % of the robots were removed at random (log)")
    axes.set_ylabel("coverage")
    axes.set_title("1,000-cell disc, 25 % spare robots: coverage through a fault")
    axes.legend()
    axes.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(path)


def pictures(strategies: list[str], cells: int, folder: Path) -> None:
    """The coverage plot (one heal per strategy, with spares) and the healing picture."""
    curves = {}
    for strategy in strategies:
        formed = form(strategy, cells, spares=True)
        curves[strategy] = heal(formed, strategy, "random")[1]
        print(strategy, "healed in", len(curves[strategy]) - 2, "steps", flush=True)
    coverage_plot(curves, folder / "fault-coverage.png")
    healing_picture(folder / "faults-healing.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strategies", nargs="+", default=["optimal", "greedy", "random", "paper"])
    parser.add_argument("--cells", type=int, default=1000)
    parser.add_argument("--on-loss", choices=("keep", "rescale"), default="keep")
    parser.add_argument("--out", type=Path, help="default docs/faults-ON_LOSS.json")
    parser.add_argument("--no-pictures", action="store_true")
    parser.add_argument(
        "--pictures-only",
        action="store_true",
        help="only the coverage plot (one heal per strategy) and the healing picture",
    )
    args = parser.parse_args()
    if args.pictures_only:
        pictures(args.strategies, args.cells, DOCS)
        return
    out = args.out or DOCS / f"faults-{args.on_loss}.json"
    results: dict = {"cells": args.cells, "seed": SEED, "share_removed": SHARE, "spares": SPARES}
    results["on_loss"] = args.on_loss
    curves = {}
    for strategy in args.strategies:
        started = time.perf_counter()
        results[strategy] = {}
        for spares in (False, True):
            formed = form(strategy, args.cells, spares, on_loss=args.on_loss)
            key = "with spares" if spares else "no spares"
            results[strategy][key] = {"formed_in": formed.step_count}
            for kind in ("random", "block"):
                figures, curve = heal(fork(formed), strategy, kind)
                results[strategy][key][kind] = figures
                if spares and kind == "random":
                    curves[strategy] = curve
                print(strategy, key, kind, figures, flush=True)
            results[strategy][key]["rate"] = under_rate(
                strategy, args.cells, spares, RATES[strategy], args.on_loss
            )
            print(strategy, key, "rate", results[strategy][key]["rate"], flush=True)
        print(f"{strategy}: {time.perf_counter() - started:.0f} s", flush=True)
        out.write_text(json.dumps(results, indent=2) + "\n")
    if not args.no_pictures:
        coverage_plot(curves, DOCS / "fault-coverage.png")
        healing_picture(DOCS / "faults-healing.png")


if __name__ == "__main__":
    main()

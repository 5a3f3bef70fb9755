"""Fault figures: how each strategy heals a 1,000-cell disc, and whether it heals every shape.
Not part of the test suite.

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

``--heal`` runs the other question, on many shapes rather than one disc: every shipped shape
(the two-group scenario too) and random shapes of one and two groups as the property tests draw
them, each formed under each strategy for seeds 0-19, then 20 % of its robots removed at random;
each must heal, or re-form smaller and heal that, within `HEAL_LIMIT` steps. With one robot
per cell and ``--on-loss keep`` a loss leaves nothing to refill (the shape is formed as far as
the survivors go), so ``--on-loss rescale`` is the run that makes them re-form. Writes
``docs/heal-ON_LOSS.json`` and prints every run that did not, with how to repeat it.

    .venv/bin/python scripts/faults.py [--strategies optimal greedy random paper] [--cells 1000]
        [--on-loss keep|rescale] [--out docs/faults-keep.json] [--no-pictures | --pictures-only]
    .venv/bin/python scripts/faults.py --heal [--on-loss rescale] [--strategies ...]
        [--seeds 20] [--jobs 2] [--shapes horse.png ...] [--random 20] [--out FILE]
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

from bench import COLOUR, SHAPES, disc, world_of
from swarmshape.config import configure
from swarmshape.core.faults import Faults
from swarmshape.core.metrics import coverage, run_metrics
from swarmshape.core.shape import Shape
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import SETTLED
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.runs import build
from swarmshape.strategies import create

DOCS = Path(__file__).resolve().parent.parent / "docs"
SHARE = 0.2
SPARES = 0.25
SEED = 1
LOCAL = ("mean-shift", "local-swap")
"""The local programs the fault figures run (`--strategies`): they form a shape in about ten
times the steps of the central ones (5 to 23 times the makespan bound against 1.5 to 2.6)."""
LIMIT = {"optimal": 20_000, "greedy": 20_000, "random": 40_000, "paper": 400_000}
LIMIT |= dict.fromkeys(LOCAL, 40_000)
RATES = {"optimal": 1e-4, "greedy": 1e-4, "random": 1e-4, "paper": 1e-6}
RATES |= dict.fromkeys(LOCAL, 1e-5)
"""Failure rate per robot per step during formation: paper's formation takes ~500 times as
many steps, so it gets a rate ~100 times lower (and the concurrent rate is reported for it
too when asked with --paper-at-concurrent-rate); local programs' ten times as many, ten
times lower."""


HEAL_LIMIT = LIMIT
"""Steps after the loss within which a run must be whole again (those of `LIMIT`: formation
takes far fewer on these shapes; a run still short by then is stuck, not slow)."""
HEAL_CELLS = {"paper": 16}
"""Cells across a shipped shape, per strategy (others: the default size, which for every
shipped shape is its own size or 32 across). The paper's one mover at a time forms the 300 to
700-cell shipped shapes in 100,000 steps and more: twenty seeds of eleven shapes would take a
day on this machine, so it forms them at 16 cells across (60 to 180 cells); `--paper-cells`
changes it."""


def heal_case(case: tuple[str, str, int, str]) -> dict:
    """Form `shape` (a shipped file, or ``random:N`` / ``random2:N``: random shapes of one
    or two groups) under `strategy` with `seed`, remove 20 % of its robots at random, and run
    until it is whole again (re-formed smaller if need be) or `HEAL_LIMIT` steps have gone."""
    shape, strategy, seed, on_loss = case
    started = time.perf_counter()
    swarm = heal_swarm(shape, strategy, seed, on_loss)
    while not swarm.complete and swarm.step_count < LIMIT[strategy]:
        swarm.step()
    formed = swarm.step_count if swarm.complete else None
    result = {"shape": shape, "strategy": strategy, "seed": seed, "formed_in": formed}
    if formed is None:
        return result | {"healed": False, "why": "did not form", "seconds": 0.0}
    present = np.flatnonzero(swarm.present)
    struck = swarm.rng.choice(present, round(SHARE * len(present)), replace=False)
    swarm.fail(np.sort(struck), "remove", label="random")
    while (
        not swarm.complete
        and not swarm.stranded
        and swarm.step_count < formed + HEAL_LIMIT[strategy]
    ):
        swarm.step()
    metrics = run_metrics(swarm)
    return result | {
        "robots_removed": len(struck),
        "healed": swarm.complete,
        "heal_steps": swarm.step_count - formed if swarm.complete else None,
        "coverage": metrics["coverage"],
        "scale": metrics["scale"],
        "targets": metrics["targets"],
        "overlaps": metrics["overlaps"],
        "why": "" if swarm.complete else ("stranded" if swarm.stranded else "out of steps"),
        "seconds": round(time.perf_counter() - started, 1),
    }


def heal_swarm(shape: str, strategy: str, seed: int, on_loss: str = "keep") -> Swarm:
    """The swarm of a `heal_case`, before its first step."""
    if shape.startswith("random"):
        groups = 2 if shape.startswith("random2") else 1
        world = random_world(np.random.default_rng(int(shape.split(":")[1])), groups)
        return Swarm(world, create(strategy), seed, Params(on_loss=on_loss))
    cells = HEAL_CELLS.get(strategy) if SHAPES.joinpath(shape).suffix == ".png" else None
    config = configure(SHAPES / shape, strategy=strategy, seed=seed, cells=cells, on_loss=on_loss)
    return build(config)


def random_world(rng: np.random.Generator, groups: int) -> World:
    """Groups as the fault property test draws them: a random 4x5 bitmap each, a few robots
    too many or too few."""
    specs = []
    spare = int(rng.integers(-3, 7))
    for index in range(groups):
        grid = rng.random((4, 5)) < 0.5
        grid[rng.integers(4), rng.integers(5)] = True
        specs.append(GroupSpec(f"g{index}", Shape(grid), COLOUR, max(1, int(grid.sum()) + spare)))
    return build_world(specs)


def heal_all(
    strategies: list[str], shapes: list[str], seeds: int, jobs: int, out: Path, on_loss: str
) -> int:
    """Every `heal_case` of these, on `jobs` processes; a summary per shape and strategy, and
    every run that did not heal, with how to repeat it."""
    import multiprocessing

    cases = [(shape, strategy, seed, on_loss) for strategy in strategies for shape in shapes
             for seed in range(seeds)]  # fmt: skip
    results = []
    with multiprocessing.Pool(jobs) as pool:
        for result in pool.imap_unordered(heal_case, cases):
            results.append(result)
            if not result["healed"]:
                print(f"NOT HEALED: {json.dumps(result)}", flush=True)
    results.sort(key=lambda r: (r["strategy"], r["shape"], r["seed"]))
    out.write_text(json.dumps(results, indent=1) + "\n")
    failed = 0
    for strategy in strategies:
        for shape in shapes:
            mine = [r for r in results if r["strategy"] == strategy and r["shape"] == shape]
            healed = [r for r in mine if r["healed"]]
            failed += len(mine) - len(healed)
            steps = [r["heal_steps"] for r in healed]
            smaller = sum(r["scale"] < 1 for r in healed)
            spread = f"{min(steps):,} to {max(steps):,}" if steps else "-"
            print(f"{strategy:8} {shape:18} healed {len(healed):2}/{len(mine)} "
                  f"(re-formed smaller {smaller}), steps {spread}")  # fmt: skip
    print(f"{len(results)} runs, {failed} not healed; {out}")
    return failed


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
    parser.add_argument("--heal", action="store_true", help="the heal-every-shape runs instead")
    parser.add_argument("--shapes", nargs="+", help="with --heal: shipped shapes (default all)")
    parser.add_argument("--random", type=int, default=20, help="with --heal: random shapes")
    parser.add_argument("--seeds", type=int, default=20, help="with --heal: seeds 0 to N-1")
    parser.add_argument("--jobs", type=int, default=2, help="with --heal: processes")
    parser.add_argument("--paper-cells", type=int, help="with --heal: cells across for paper")
    args = parser.parse_args()
    if args.paper_cells is not None:
        HEAL_CELLS["paper"] = args.paper_cells
    if args.heal:
        shipped = args.shapes or sorted(
            p.name for p in SHAPES.iterdir() if p.suffix in (".png", ".toml")
        )
        shapes = shipped + [f"{kind}:{n}" for kind in ("random", "random2")
                            for n in range(args.random)]  # fmt: skip
        out = args.out or DOCS / f"heal-{args.on_loss}.json"
        failed = heal_all(args.strategies, shapes, args.seeds, args.jobs, out, args.on_loss)
        sys.exit(1 if failed else 0)
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

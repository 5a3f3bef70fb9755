"""Benchmark formation against what no run can beat: prints issue 11's table, writes JSON.

    nice .venv/bin/python scripts/bench.py [--out FILE] [--quick] [--million]

Every figure is measured in this one run, on this machine, with seed 1 and the default
`optimal` strategy at default limits (speed 0.5, acceleration 0.125) unless a row says
otherwise. The ratio is steps to form over the metrics' makespan lower bound: the time from
rest to rest under those limits of the bottleneck trip, exact or a proved bound as the
"bound" column says. The old figures are the ones issue 11 measured before the work on it
(its "Hall bound" column where the reported bound was the nearest-robot fallback); their
ratios divide by trip length over the top speed, which ignores acceleration and so is a
lower bound than today's: the new ratios are the stricter of the two.

The formations include the horse at 20,000 cells (issue 32 tried pictures at 9,000 to 23,000
cells). Beside them: the same 1,000-robot block stepped by a plain pygame sprite loop and a
Mesa 3 model (`scripts/reference_loops.py`, from the shell; Mesa only when installed, the
`bench` extra), a local program's step at 10,000 robots, and the learning environment's
batched step (`scripts/bench_env.py`), each with issue 32's figure from before its work.

`--quick` runs the 1,000-robot rows and the fixed-cost rows only (about 30 s);
`--million` adds a 1,000,000-robot disc run from the shell under a time cap (`--cap`);
`--caps` runs only the inputs at the caps (issue 29): shapes fitted to few robots, the largest
arena, the largest pictures, a million start cells and a state that unpacks to 3 GB, each from
the shell with its own wall time and peak memory.
Targets live here and only here: a benchmark, not a timed test.
"""

from __future__ import annotations

import argparse
import gc
import importlib.metadata
import importlib.util
import io
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass
from datetime import date
from pathlib import Path

import numpy as np
import numpy.lib.format as npy
from PIL import Image

from swarmshape.config import RunConfig
from swarmshape.core.assignment import optimal
from swarmshape.core.bounds import unit_speed_optimum
from swarmshape.core.metrics import run_metrics
from swarmshape.core.shape import Shape
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.io.bitmap import load_grid
from swarmshape.runs import Observer, Runner, load_world, save, start_swarm

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "shapes"
COLOUR = (58, 111, 216)
MAX_STEPS = 200_000

RATIO_TARGET = 2.0  # steps / makespan lower bound, every shape and size (moonshot 1.5)
UNIT_TARGET = 1.3  # steps / exact unit-speed optimum
BLOCK_SHELL_SECONDS = 0.6
DISC_100K_SHELL_SECONDS = 60.0
STEPPING_TARGETS = {1000: 5000.0, 100_000: 100.0}  # steps/s over the first 20 steps (issue 32)
MILLION_MOONSHOT = (600.0, 8.0)  # seconds, GB
REFERENCE_TARGETS = {"sprites": 300.0, "mesa": 100.0}  # times swarmshape's steps/s (issue 32)
MESA_SHELL_TARGET = 20.0  # Mesa's whole process over swarmshape's, for as many steps
LOCAL_STEP_MS = 20.0  # a local program's step at 10,000 robots
LOCAL_PROGRAMS = ("local-swap", "mean-shift", "self-assembly")
ENV_TARGET = 1500.0  # the learning environment, batched, 1,000 robots, steps/s
OLD_32 = {  # issue 32's figures, measured before its work
    "stepping": "1,384 to 1,404 steps/s idle, about 1,000 under load",
    "sprites": "154x",
    "mesa": "34x",
    "mesa shell": "4.3x",
    "block shell": "1.2 s idle, 1.8 s under load",
    "disc shell": "65 s idle, 192 s under load",
    "local step": "70 to 130 ms",
    "environment": "534 to 537 steps/s idle, 331 under load",
}
"""Issue 32 did not keep its sprite loop and Mesa model: the ones in `scripts/` are new, so
their ratios do not compare with its figures one for one."""
CAPS = {  # name: (arguments, seconds, GB): an input at the caps, from the shell
    "fit 2,000 cells across to 5 robots": (["horse.png", "--cells", "2000", "--agents", "5",
                                            "--preview"], 10.0, 0.5),
    "fit 3,000 cells across to 5 robots": (["horse.png", "--cells", "3000", "--agents", "5",
                                            "--preview"], 15.0, 0.8),
    "arena 5000x5000, 20 robots, 3 steps": (["line.png", "--arena", "5000x5000", "--agents",
                                             "20", "--headless", "--max-steps", "3"], 60.0, 2.0),
    "1 x 25,000,000 picture, preview": (["long.png", "--preview"], 15.0, 0.6),
    "5000x5000 picture without ink": (["white.png", "--preview"], 10.0, 0.5),
    "1,000,000 start cells for 16 robots": (["line.png", "--start", "million.csv",
                                             "--headless", "--max-steps", "1"], 4.0, 0.3),
    "state that unpacks to 3 GB": (["--load-state", "bomb.state", "--headless"], 3.0, 0.2),
}  # fmt: skip
"""Issue 29 measured 3 and over 15 minutes for the fits, 3 GB for the arena, 2 GB and 1.7 GB
for the pictures, 11 s for the start cells and 3 GB and 9 s for the state."""

OLD = {  # issue 11's measurements before the change: steps, ratio, wall seconds
    ("block", 1000): (220, 2.2, 3.4),
    ("star", 1000): (451, 4.5, None),
    ("disc", 10_000): (1909, 5.5, 4.8),
    ("horse", 10_000): (2618, 9.6, None),
    ("disc", 100_000): (19_025, 17.4, 285.0),
}
"""Issue 11 also measured a grey photo at --cells 250 (22,628 robots, 6,059 steps, 14.2x);
that photo is not in the repository, so the horse silhouette stands for photos here."""


@dataclass(frozen=True)
class Case:
    name: str
    robots: int  # the size class: about this many robots

    def grid(self) -> np.ndarray:
        if self.name == "disc":
            return disc(self.robots)
        if self.name == "block":
            return np.ones((50, 20), dtype=bool)
        return load_grid(SHAPES / f"{PICTURES[self.name]}.png", cells=cells_for(self))


PICTURES = {"star": "star", "ring": "ring", "letter": "letter-s", "horse": "horse"}


def disc(cells: int) -> np.ndarray:
    """A round shape of exactly `cells` cells, indexed [x, y]."""
    side = int(2 * np.sqrt(cells / np.pi)) + 3
    y, x = np.mgrid[:side, :side] - side / 2 + 0.5
    distance = np.hypot(x, y).ravel()
    grid = np.zeros(side * side, dtype=bool)
    grid[np.argsort(distance, kind="stable")[:cells]] = True
    return grid.reshape(side, side)


def cells_for(case: Case) -> int:
    """The `--cells` that gives the picture about `case.robots` cells (area grows as its square)."""
    path = SHAPES / f"{PICTURES[case.name]}.png"
    cells = 32
    for _ in range(3):
        count = int(load_grid(path, cells=cells).sum())
        cells = max(4, round(cells * np.sqrt(case.robots / count)))
    return cells


def world_of(grid: np.ndarray, agents: int | None = None) -> World:
    """One group forming `grid`, with `agents` robots (default: one per cell)."""
    return build_world([GroupSpec("bench", Shape(grid), COLOUR, agents)])


class Watch(Observer):
    """The first step at which coverage reached 90 %."""

    def __init__(self) -> None:
        self.at_90: int | None = None

    def capture(self, swarm: Swarm) -> None:
        if self.at_90 is None and swarm.filled.mean() >= 0.9:
            self.at_90 = swarm.step_count


def formation(case: Case, speed: float = 0.5, accel: float = 0.125) -> dict:
    """One run in this process: build, step to the end, metrics; wall time of all three."""
    grid = case.grid()
    started = time.perf_counter()
    world = world_of(grid)
    swarm = start_swarm(RunConfig(seed=1, max_speed=speed, max_accel=accel), world)
    watch = Watch()
    Runner(swarm, [watch], MAX_STEPS).finish()
    metrics = run_metrics(swarm)
    seconds = time.perf_counter() - started
    row = {
        "shape": case.name,
        "size": case.robots,
        "robots": int(world.agents),
        "steps_90": watch.at_90,
        "steps": metrics["steps"],
        "bound": metrics["makespan_lower_bound"],
        "bound_cells": metrics["makespan_bound_cells"],
        "bound_method": metrics["makespan_bound_method"],
        "bound_exact": metrics["makespan_bound_exact"],
        "ratio": metrics["makespan_ratio"],
        "distance_ratio": metrics["distance_ratio"],
        "distance_bound_method": metrics["distance_bound_method"],
        "overlaps": metrics["overlaps"],
        "seconds": round(seconds, 2),
    }
    old = OLD.get((case.name, case.robots))
    if old:
        row["old_steps"], row["old_ratio"], row["old_seconds"] = old
    return row


def unit_speed(case: Case) -> dict:
    """Steps at one cell a step without acceleration, against the exact max-flow optimum."""
    grid = case.grid()
    world = world_of(grid)
    swarm = start_swarm(RunConfig(seed=1, max_speed=1.0, max_accel=1.0), world)
    Runner(swarm, [], MAX_STEPS).finish()
    passable = ~world.mask(world.seeds)
    started = time.perf_counter()
    optimum = unit_speed_optimum(passable, swarm.start_cell, world.targets, upper=swarm.step_count)
    return {
        "shape": case.name,
        "robots": int(world.agents),
        "steps": swarm.completed_at[0],
        "optimum": optimum,
        "ratio": round(swarm.completed_at[0] / optimum, 3),
        "optimum_seconds": round(time.perf_counter() - started, 2),
    }


def stepping(grid: np.ndarray, steps: int = 20) -> dict:
    """Steps per second over the first `steps` steps, when every robot is still moving, of a
    swarm started afresh after the same steps of another: loading the compiled kernels and
    filling the process's caches (about 160 ms, once per process) is a start-up cost, which
    the rows from the shell count, not a step's."""
    world = world_of(grid)
    for _ in range(2):
        swarm = start_swarm(RunConfig(seed=1), world)
        started = time.perf_counter()
        for _ in range(steps):
            swarm.step()
        seconds = time.perf_counter() - started
    return {"robots": int(world.agents), "steps": steps, "steps_per_s": round(steps / seconds, 1)}


def side_by_side(folder: Path, ours: dict, shell: dict) -> list[dict]:
    """The 1,000-robot block stepped by `scripts/reference_loops.py`'s sprite loop and Mesa
    model, each from the shell, with the robots, start cells and targets of the `stepping` row
    (`ours`): its steps/s over as many first steps, against swarmshape's (whose first steps
    start robots in turn, where the loops move every robot from the first); and its whole
    process for as many steps as swarmshape's run from the shell (`shell`) took to form,
    against that run's wall time. The second is rough: the loop reads targets worked out here,
    where swarmshape's run pays for its exact assignment, and it starts from this row's cells,
    not the command line's own."""
    world = world_of(Case("block", 1000).grid())
    swarm = start_swarm(RunConfig(seed=1), world)
    assert len(swarm.start_cell) == len(world.targets)  # one robot a cell: each gets a goal
    goal = np.empty_like(swarm.start_cell)
    goal[optimal(swarm.start_cell, world.targets, np.random.default_rng(1))] = world.targets
    scenario = folder / "block.npz"
    np.savez(scenario, size=np.array(world.size), start=swarm.start_cell, goal=goal)
    rows = []
    for loop in ("sprites", "mesa"):
        row: dict = {"loop": loop, "missing": _missing(loop)}
        rows.append(row)
        if row["missing"]:
            continue
        try:
            first, _ = _reference(loop, scenario, ours["steps"])
            steps_per_s = ours["steps"] / first["seconds"]
            row["steps_per_s"] = round(steps_per_s, 1)
            row["swarmshape_times_as_fast"] = round(ours["steps_per_s"] / steps_per_s, 1)
            if shell.get("steps"):  # a run from the shell that formed
                _, whole = _reference(loop, scenario, shell["steps"])
                row["shell_steps"], row["shell_seconds"] = shell["steps"], round(whole, 2)
                row["times_longer_from_shell"] = round(whole / shell["seconds"], 1)
        except subprocess.CalledProcessError as failed:
            row["failed"] = (failed.stderr.strip().splitlines() or ["no message"])[-1]
    return rows


def _missing(loop: str) -> str | None:
    """What a reference loop lacks to run here (None: nothing): Mesa is an extra."""
    if loop != "mesa":
        return None
    try:
        major = int(importlib.metadata.version("mesa").split(".")[0])
    except importlib.metadata.PackageNotFoundError:
        return "not installed: pip install -e '.[bench]'"
    return None if major >= 3 else "Mesa 3 needed: pip install -e '.[bench]'"


def _reference(loop: str, scenario: Path, steps: int) -> tuple[dict, float]:
    """One reference loop from the shell: what it printed, and its whole wall time."""
    script = Path(__file__).resolve().parent / "reference_loops.py"
    command = [sys.executable, str(script), loop, str(scenario), "--steps", str(steps)]
    started = time.perf_counter()
    done = subprocess.run(command, check=True, capture_output=True, text=True)
    return json.loads(done.stdout), time.perf_counter() - started


def local_step(strategy: str, warm: int = 100, steps: int = 20) -> dict:
    """A local program's whole step (sensing, the program, claims, moving, the audit) at
    10,000 robots: the 9,946-robot letter S from the default start, seed 1, CPU time per step
    over `steps` steps after `warm` (a step costs more as robots gather: at steps 1-20 about
    two thirds of this)."""
    world = world_of(Case("letter", 10_000).grid())
    swarm = start_swarm(RunConfig(seed=1, strategy=strategy), world)
    for _ in range(warm):
        swarm.step()
    # the swarms of the rows before are garbage held in reference cycles: collected while
    # this one steps, they added 4 to 10 ms to each of its steps at 10,000 robots
    gc.collect()
    started = time.process_time()
    for _ in range(steps):
        swarm.step()
    per_step = (time.process_time() - started) / steps
    return {"strategy": strategy, "robots": int(world.agents), "after": warm,
            "ms_per_step": round(per_step * 1000, 1)}  # fmt: skip


def environment() -> dict:
    """The learning environment's batched step at 1,000 robots (`scripts/bench_env.py`), if
    its extra is installed."""
    if not all(importlib.util.find_spec(name) for name in ("gymnasium", "pettingzoo")):
        return {"robots": 1000, "missing": "not installed: pip install -e '.[learn]'"}
    from bench_env import batched_rate

    wall, cpu = batched_rate()
    return {"robots": 1000, "missing": None, "steps_per_s": round(wall, 1),
            "cpu_steps_per_s": round(cpu, 1)}  # fmt: skip


def from_shell(grid: np.ndarray, folder: Path, cap: float | None = None) -> dict:
    """`swarmshape PNG --headless` in a fresh process, as a user runs it: wall time, peak
    memory (the child's maximum resident set), and its metrics; or that it hit `cap`."""
    xs, ys = np.flatnonzero(grid.any(axis=1)), np.flatnonzero(grid.any(axis=0))
    grid = grid[xs[0] : xs[-1] + 1, ys[0] : ys[-1] + 1]  # the loader crops to the ink too
    image = folder / f"shape-{grid.sum()}.png"
    Image.fromarray(np.where(grid.T, 0, 255).astype(np.uint8)).save(image)
    metrics = folder / f"metrics-{grid.sum()}.json"
    command = [
        str(Path(sys.executable).parent / "swarmshape"),
        str(image),
        "--headless",
        "--cells",
        str(max(grid.shape)),
        "--seed",
        "1",
        "--max-steps",
        str(MAX_STEPS),
        "--metrics",
        str(metrics),
        "--force",
    ]
    started = time.perf_counter()
    try:
        subprocess.run(command, check=True, capture_output=True, timeout=cap)
    except subprocess.TimeoutExpired as stopped:
        said = (stopped.stderr or b"").decode(errors="replace").strip().splitlines()
        return {
            "robots": int(grid.sum()),
            "finished": False,
            "cap_seconds": cap,
            "peak_gb": _peak_gb(),
            "bytes_per_robot": round(_peak_gb() * 1e9 / grid.sum()),
            "last_progress": said[-1] if said else None,  # a line every 10 s off a terminal
        }
    seconds = time.perf_counter() - started
    peak = _peak_gb()
    found = json.loads(metrics.read_text())
    return {
        "robots": found["agents"],
        "finished": found["steps"] is not None,
        "seconds": round(seconds, 2),
        "peak_gb": peak,
        "bytes_per_robot": round(peak * 1e9 / found["agents"]),
        "steps": found["steps"],
        "ratio": found["makespan_ratio"],
        "bound_method": found["makespan_bound_method"],
    }


def caps(folder: Path) -> list[dict]:
    """Each of `CAPS` in a fresh ``swarmshape`` process: its wall time, its own peak memory
    (the child's maximum resident set, from wait4) and its exit status."""
    _cap_inputs(folder)
    rows = []
    for name, (arguments, seconds_goal, gb_goal) in CAPS.items():
        first = arguments[0]
        if first.endswith(".png") and (SHAPES / first).exists():
            arguments = [str(SHAPES / first), *arguments[1:]]
        command = [str(Path(sys.executable).parent / "swarmshape"), *arguments]
        started = time.perf_counter()
        child = subprocess.Popen(command, cwd=folder, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE)  # fmt: skip
        _, status, usage = os.wait4(child.pid, 0)
        seconds = time.perf_counter() - started
        said = child.stderr.read().decode(errors="replace").strip()
        child.stderr.close()
        rows.append({
            "case": name, "seconds": round(seconds, 2), "peak_gb": round(usage.ru_maxrss / 1e6, 2),
            "exit": os.waitstatus_to_exitcode(status), "said": said.splitlines()[-1:] or [""],
            "seconds_goal": seconds_goal, "gb_goal": gb_goal,
        })  # fmt: skip
        print_cap(rows[-1], flush=True)
    return rows


def _cap_inputs(folder: Path) -> None:
    """The inputs of `CAPS` that are not shipped: pictures, start cells, a state bomb."""
    Image.new("L", (25_000_000, 1), 0).save(folder / "long.png")
    Image.new("L", (5000, 5000), 255).save(folder / "white.png")
    (folder / "million.csv").write_text("x,y\n" + "1,1\n" * 1_000_000)
    config = RunConfig(shape=SHAPES / "star.png", seed=1)
    world = load_world(config)
    swarm = Runner(start_swarm(config, world), max_steps=5).finish()
    save(swarm, folder / "small.state", config)
    with (
        zipfile.ZipFile(folder / "small.state") as small,
        zipfile.ZipFile(folder / "bomb.state", "w", zipfile.ZIP_DEFLATED) as bomb,
    ):
        for info in small.infolist():
            if info.filename != "swarm.driver.planner.rows.npy":
                bomb.writestr(info, small.read(info))
        cells = world.size[0] * world.size[1]
        shape = (3 * 2**30 // (8 * cells), cells)
        header = io.BytesIO()
        npy.write_array_header_2_0(header, {"descr": "<f8", "fortran_order": False,
                                            "shape": shape})  # fmt: skip
        with bomb.open("swarm.driver.planner.rows.npy", "w", force_zip64=True) as member:
            member.write(header.getvalue())
            zeros, left = bytes(2**24), shape[0] * shape[1] * 8
            while left:
                member.write(zeros[: min(left, len(zeros))])
                left -= min(left, len(zeros))


def print_cap(row: dict, flush: bool = False) -> None:
    seconds = _against(row["seconds"], row["seconds_goal"], "<=")
    memory = _against(row["peak_gb"], row["gb_goal"], "<=")
    print(
        f"  {row['case']:<38} {row['seconds']:>7.2f} s{seconds}  {row['peak_gb']:>5.2f} GB"
        f"{memory}  exit {row['exit']}: {row['said'][0][:70]}",
        flush=flush,
    )


def _peak_gb() -> float:
    """The largest resident set of any child process so far (Linux counts it in kB)."""
    return round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e6, 2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out",
        type=Path,
        help="where the figures go (default docs/bench.json; docs/bench-quick.json with "
        "--quick and docs/caps.json with --caps, so that neither replaces the full run's)",
    )
    parser.add_argument("--quick", action="store_true", help="1,000 robots and fixed costs only")
    parser.add_argument("--million", action="store_true", help="add 1,000,000 robots, capped")
    parser.add_argument("--cap", type=float, default=1800.0, help="seconds for --million")
    parser.add_argument("--caps", action="store_true", help="only the inputs at the caps")
    args = parser.parse_args()
    if args.cap <= 0:
        parser.error("--cap must be above 0")
    if args.caps:
        with tempfile.TemporaryDirectory() as scratch:
            rows = caps(Path(scratch))
        out = args.out or ROOT / "docs" / "caps.json"
        out.write_text(
            json.dumps({"date": date.today().isoformat(), "caps": rows}, indent=2) + "\n"
        )
        print(f"\nwritten to {out}")
        return
    shapes = ["disc", "star", "ring", "letter", "horse"]
    sizes = [1000] if args.quick else [1000, 10_000]
    results: dict = {
        "date": date.today().isoformat(),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}",
        "load_average": os.getloadavg()[0],
    }
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        results["shell"] = [{"case": "block", **from_shell(Case("block", 1000).grid(), folder)}]
        results["stepping"] = [stepping(Case("block", 1000).grid())]
        results["side_by_side"] = side_by_side(folder, results["stepping"][0], results["shell"][0])
        results["environment"] = [environment()]
        cases = [Case("block", 1000)] + [Case(s, n) for n in sizes for s in shapes]
        if not args.quick:  # a picture the size issue 32 tried pictures at, 9,000 to 23,000
            cases.append(Case("horse", 20_000))
        results["formation"] = []
        for case in cases:
            results["formation"].append(formation(case))
            print_row(results["formation"][-1], flush=True)
        results["unit_speed"] = [unit_speed(c) for c in (Case("disc", 300), Case("disc", 1000))]
        if not args.quick:
            results["unit_speed"].append(unit_speed(Case("star", 1000)))
            results["local_step"] = [local_step(strategy) for strategy in LOCAL_PROGRAMS]
            results["stepping"].append(stepping(disc(100_000)))
            big = formation(Case("disc", 100_000))
            results["formation"].append(big)
            print_row(big, flush=True)
            results["shell"].append({"case": "disc", **from_shell(disc(100_000), folder)})
        if args.million:
            results["shell"].append(
                {"case": "disc", **from_shell(disc(1_000_000), folder, cap=args.cap)}
            )
    results["load_average_after"] = os.getloadavg()[0]
    out = args.out or ROOT / "docs" / ("bench-quick.json" if args.quick else "bench.json")
    out.write_text(json.dumps(results, indent=2) + "\n")
    print_table(results)
    print(f"\nwritten to {out}")


def print_row(row: dict, flush: bool = False) -> None:
    exact = "exact" if row["bound_exact"] else f"{row['bound_method']}, not exact"
    ratio = "-" if row["ratio"] is None else f"{row['ratio']:.2f}x"
    old = ""
    if "old_steps" in row:
        old = f"{row['old_steps']:,} / {row['old_ratio']}x"
    print(
        f"  {row['shape']:<6} {row['robots']:>7,}  {row['steps_90']!s:>6} {row['steps']!s:>6}"
        f"  {row['bound']:>5} ({exact:<22}) {ratio:>6}{_against(row['ratio'], RATIO_TARGET, '<=')}"
        f"  {row['seconds']:>6.1f} s  {old}",
        flush=flush,
    )


def print_table(results: dict) -> None:
    print(f"\nswarmshape benchmark, {results['date']}, {results['machine']}")
    print(f"load average {results['load_average']:.1f} at start\n")
    print("formation (seed 1, optimal, speed 0.5, accel 0.125): target ratio <= 2.0")
    print("  shape   robots  90 %   100 %  bound (method)                 ratio  run time  old")
    for row in results["formation"]:
        print_row(row)
    print("\nunit speed (max-speed 1, max-accel 1) against the exact max-flow optimum")
    for row in results["unit_speed"]:
        verdict = _against(row["ratio"], UNIT_TARGET, "<=")
        print(
            f"  {row['shape']:<6} {row['robots']:>7,}  {row['steps']} / {row['optimum']}"
            f" = {row['ratio']:.2f}{verdict}"
        )
    print("\nstepping, first 20 steps, every robot moving")
    for row in results["stepping"]:
        goal = STEPPING_TARGETS.get(row["robots"])
        print(
            f"  {row['robots']:>9,} robots  {row['steps_per_s']:>8.0f} steps/s"
            f"{_against(row['steps_per_s'], goal, '>=')}"
        )
    print(f"  before issue 32's work: {OLD_32['stepping']}")
    print_side_by_side(results["side_by_side"])
    print("\nlearning environment, batched, 1,000 robots (scripts/bench_env.py, best of 3)")
    for row in results["environment"]:
        if row["missing"]:
            print(f"  {row['missing']}")
            continue
        verdict = _against(row["steps_per_s"], ENV_TARGET, ">=")
        print(
            f"  {row['steps_per_s']:>8.0f} steps/s wall{verdict}, {row['cpu_steps_per_s']:.0f}"
            f" in CPU time; before: {OLD_32['environment']}"
        )
    if "local_step" in results:
        print("\na local program's step at 10,000 robots (letter S, default start), CPU")
        for row in results["local_step"]:
            print(
                f"  {row['strategy']:<14} {row['robots']:,} robots, steps {row['after'] + 1} on:"
                f" {row['ms_per_step']:>6.1f} ms{_against(row['ms_per_step'], LOCAL_STEP_MS, '<=')}"
            )
        print(f"  before issue 32's work: {OLD_32['local step']}")
    print("\nwall time from the shell (swarmshape PNG --headless: the CLI's own world, so its")
    print("start cells, and steps, differ from the in-process row of the same shape)")
    for row in results["shell"]:
        if not row["finished"]:
            cap, last = row["cap_seconds"], row["last_progress"]
            print(
                f"  {row['case']:<6} {row['robots']:>9,}  not finished within {cap:g} s"
                f" (peak {row['peak_gb']:.2f} GB, {row['bytes_per_robot']:,} bytes a robot;"
                f" last said: {last})"
            )
            continue
        goal = {1000: BLOCK_SHELL_SECONDS, 100_000: DISC_100K_SHELL_SECONDS}.get(
            round(row["robots"], -3)
        )
        before = OLD_32.get(f"{row['case']} shell") if row["robots"] <= 100_000 else None
        print(
            f"  {row['case']:<6} {row['robots']:>9,}  {row['seconds']:>7.2f} s"
            f"{_against(row['seconds'], goal, '<=')}  peak {row['peak_gb']:.2f} GB"
            f" ({row['bytes_per_robot']:,} bytes a robot),"
            f" {row['steps']} steps, {row['ratio']:.2f}x ({row['bound_method']})"
            + (f"; before: {before}" if before else "")
        )


def print_side_by_side(rows: list[dict]) -> None:
    print("\nthe same block stepped by scripts/reference_loops.py (no planning, whole cells)")
    for row in rows:
        name = {"sprites": "pygame sprite loop", "mesa": "Mesa 3 model"}[row["loop"]]
        if row["missing"] or "failed" in row:
            print(f"  {name:<18}  {row['missing'] or 'failed: ' + row['failed']}")
            continue
        goal = REFERENCE_TARGETS[row["loop"]]
        times = row["swarmshape_times_as_fast"]
        print(
            f"  {name:<18}  {row['steps_per_s']:>8.0f} steps/s: swarmshape is {times:g}x as fast"
            f"{_against(times, goal, '>=')}; before: {OLD_32[row['loop']]}"
        )
        if "shell_seconds" not in row:
            continue
        verdict, before = "", ""
        if row["loop"] == "mesa":
            verdict = _against(row["times_longer_from_shell"], MESA_SHELL_TARGET, ">=")
            before = f"; before: {OLD_32['mesa shell']}"
        print(
            f"  {'':<18}  from the shell, {row['shell_steps']} steps: {row['shell_seconds']:.2f} s,"
            f" {row['times_longer_from_shell']:g}x swarmshape's formed run{verdict}{before}"
        )


def _against(value: float | None, goal: float | None, sense: str) -> str:
    if goal is None or value is None:
        return ""
    met = value >= goal if sense == ">=" else value <= goal
    return f" [{sense} {goal:g}: {'met' if met else 'MISSED'}]"


if __name__ == "__main__":
    main()

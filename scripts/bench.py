"""Benchmark swarmshape on this machine: prints a table and writes the figures as JSON.

    .venv/bin/python scripts/bench.py [--out bench.json] [--quick]

Every figure is measured in this one run, next to the target it is held to. Steps per second
are taken over the first steps of a formation, when every agent is still moving (the slowest
part). Not a test: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from collections.abc import Callable
from datetime import date
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import numpy as np
import pygame

from swarmshape.core import assignment
from swarmshape.core.metrics import run_metrics
from swarmshape.core.shape import Shape
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.io.bitmap import load_grid
from swarmshape.runs import RunConfig, run, start_swarm
from swarmshape.strategies.fill_order import fill_sequence
from swarmshape.ui.render import Renderer

SHAPES = Path(__file__).resolve().parent.parent / "shapes"
COLOUR = (58, 111, 216)


def disc(cells: int) -> np.ndarray:
    """A round shape of exactly `cells` cells."""
    side = int(2 * np.sqrt(cells / np.pi)) + 3
    y, x = np.mgrid[:side, :side] - side / 2 + 0.5
    distance = np.hypot(x, y).ravel()
    grid = np.zeros(side * side, dtype=bool)
    grid[np.argsort(distance, kind="stable")[:cells]] = True
    return grid.reshape(side, side)


def world_of(grid: np.ndarray, agents: int | None = None) -> World:
    return build_world([GroupSpec("bench", Shape(grid), COLOUR, agents)])


def swarm_of(world: World, strategy: str = "optimal") -> Swarm:
    return start_swarm(RunConfig(strategy=strategy, seed=1), world)


def timed(action: Callable[[], object]) -> float:
    start = time.perf_counter()
    action()
    return time.perf_counter() - start


def steps_per_second(agents: int, steps: int) -> dict:
    world = world_of(disc(agents))
    swarm = swarm_of(world)
    seconds = timed(lambda: run(swarm, max_steps=steps))
    return {"agents": agents, "steps": swarm.step_count, "steps_per_s": swarm.step_count / seconds}


def frame_time(agents: int, frames: int) -> dict:
    world = world_of(disc(agents))
    swarm = swarm_of(world)
    pygame.display.init()
    surface = pygame.Surface((1280, 800))
    renderer = Renderer(world)
    renderer.draw(surface, swarm)

    def frame() -> None:
        for _ in range(frames):
            swarm.step()
            renderer.draw(surface, swarm)

    return {"agents": agents, "frame_ms": 1000 * timed(frame) / frames}


def assignment_times(agents: int) -> dict:
    world = world_of(disc(agents))
    rng = np.random.default_rng(1)
    starts = world.start_cells()
    cells = starts[rng.choice(len(starts), agents, replace=False)].astype(np.float64)
    targets = world.targets.astype(np.float64)
    row = {"agents": agents}
    for name, match in (
        ("optimal", assignment.optimal),
        ("greedy", assignment.greedy),
        ("random", assignment.random_assignment),
    ):
        row[name] = timed(lambda match=match: match(cells, targets, rng))
    row["paper (fill order)"] = timed(lambda: fill_sequence(world, 0, "outward", rng))
    if agents * agents > assignment.EXACT_LIMIT:  # how far bisection is from exact, measured
        row["optimal_vs_exact"] = _bisection_gap(rng)
    return row


def _bisection_gap(rng: np.random.Generator) -> float:
    """Total squared distance of bisection over exact, on the largest exact-size case."""
    world = world_of(disc(1000))
    starts = world.start_cells()
    cells = starts[rng.choice(len(starts), 1000, replace=False)].astype(np.float64)
    targets = world.targets.astype(np.float64)
    exact = assignment.optimal(cells, targets, rng)
    approximate = assignment._by_parts(cells, targets, assignment.LEAF, assignment._hungarian)
    return float(
        ((cells[approximate] - targets) ** 2).sum() / ((cells[exact] - targets) ** 2).sum()
    )


def formation(name: str, grid: np.ndarray, strategies: list[str], max_steps: int) -> list[dict]:
    world = world_of(grid)
    rows = []
    for strategy in strategies:
        swarm = swarm_of(world, strategy)
        seconds = timed(lambda swarm=swarm: run(swarm, max_steps=max_steps))
        metrics = run_metrics(swarm)
        rows.append(
            {
                "shape": name,
                "cells": int(grid.sum()),
                "strategy": strategy,
                "steps": metrics["steps"],
                "coverage": metrics["coverage"],
                "overlaps": metrics["overlaps"],
                "makespan_lower_bound": metrics["makespan_lower_bound"],
                "makespan_ratio": metrics["makespan_ratio"],
                "distance_ratio": metrics["distance_ratio"],
                "seconds": seconds,
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("bench.json"))
    parser.add_argument("--quick", action="store_true", help="skip 100,000 agents and paper")
    args = parser.parse_args()
    big = [] if args.quick else [100_000]
    concurrent = ["optimal", "greedy", "random"]
    results = {
        "date": date.today().isoformat(),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}",
        "steps_per_second": [steps_per_second(n, 400) for n in (100, 1000)]
        + [steps_per_second(n, 100) for n in (10_000, *big)],
        "frame": [frame_time(1000, 100), frame_time(10_000, 30)],
        "assignment_seconds": [assignment_times(n) for n in (1000, *big)],
        "formation_1000": formation("disc", disc(1000), concurrent, 20_000)
        + formation("star", load_grid(SHAPES / "star.png", cells=56), concurrent, 20_000),
        "formation_100": formation(
            "disc", disc(100), (concurrent if args.quick else [*concurrent, "paper"]), 200_000
        ),
    }
    if not args.quick:
        results["formation_1000"] += formation("disc", disc(1000), ["paper"], 400_000)
    paper = [r for r in results["formation_100"] if r["strategy"] == "paper"]
    if paper:
        best = min(r["steps"] for r in results["formation_100"] if r["strategy"] != "paper")
        results["speedup_at_100"] = paper[0]["steps"] / best
    args.out.write_text(json.dumps(results, indent=2) + "\n")
    print_table(results)
    print(f"\nwritten to {args.out}")


def print_table(results: dict) -> None:
    print(f"swarmshape benchmark, {results['date']}, {results['machine']}\n")
    targets = {1000: 2000, 10_000: 400, 100_000: 25}
    print("headless steps/s (optimal, all agents moving)")
    for row in results["steps_per_second"]:
        goal = targets.get(row["agents"])
        verdict = _against(row["steps_per_s"], goal, ">=")
        print(f"  {row['agents']:>7,} agents  {row['steps_per_s']:>8.0f}{verdict}")
    print("simulate + draw one 1280x800 frame")
    for row in results["frame"]:
        goal = {1000: 2.0, 10_000: 16.7}[row["agents"]]
        verdict = _against(row["frame_ms"], goal, "<=")
        print(f"  {row['agents']:>7,} agents  {row['frame_ms']:>6.2f} ms{verdict}")
    print("assignment time (s)")
    for row in results["assignment_seconds"]:
        cells = "  ".join(
            f"{key} {value:.3f}"
            for key, value in row.items()
            if key not in ("agents", "optimal_vs_exact")
        )
        print(f"  {row['agents']:>7,} agents  {cells}")
        if "optimal_vs_exact" in row:
            gap = row["optimal_vs_exact"]
            print(f"{'':18}bisection total / exact total at 1,000: {gap:.4f}")
    print("formation: steps (ratio to the makespan lower bound), coverage, overlaps")
    for row in results["formation_1000"] + results["formation_100"]:
        ratio = "-" if row["makespan_ratio"] is None else f"{row['makespan_ratio']:.2f}x"
        print(
            f"  {row['shape']:<5} {row['cells']:>5} cells  {row['strategy']:<8} "
            f"{row['steps']!s:>7} ({ratio})  coverage {row['coverage']:.3f}  "
            f"overlaps {row['overlaps']}  {row['seconds']:.1f} s"
        )
    if "speedup_at_100" in results:
        speedup = results["speedup_at_100"]
        print(f"concurrent over paper at 100 agents: {speedup:.1f}x fewer steps (target >= 20x)")


def _against(value: float, goal: float | None, sense: str) -> str:
    if goal is None:
        return ""
    met = value >= goal if sense == ">=" else value <= goal
    return f"   target {sense} {goal:g}: {'met' if met else 'MISSED'}"


if __name__ == "__main__":
    main()

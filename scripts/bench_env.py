"""Benchmark the learning environment: environment steps per second at 1,000 robots.

    .venv/bin/python scripts/bench_env.py [--robots 1000] [--steps 300]

Random moves from pre-drawn arrays (the policy costs nothing), on a disc of as many cells as
robots, starting from the first step (robots spread round the shape). Three figures, each the
best of three runs, as wall-clock and as this process's CPU time (on a shared machine the wall
clock also counts other people's work):
- the batched interface (`vector_env`): what issue 32 holds to 1,500 steps/s (issue 14: 500);
- the same swarm stepped by the relay alone, sensing but not encoding observations: the
  simulator's own cost of a step of a local program;
- the same, with the robots packed in a square block (about 25 neighbours each, as in a formed
  shape, against about 5 at the start of a formation): observations are then mostly full;
- the PettingZoo interface (a dict per robot per step), for comparison;
- and, to show how busy the machine is, `scripts/bench.py`'s stepping figure (the central
  ``optimal`` strategy's first steps) on the same disc, as in the README's table.
Not a test: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import warnings
from collections.abc import Callable
from typing import Any

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import numpy as np

from bench import disc, stepping
from swarmshape.env import SwarmVectorEnv, parallel_env, vector_env
from swarmshape.io.bitmap import ShapeWarning

TARGET = 1500


def timed(run: Callable[[], int]) -> tuple[float, float]:
    """Best steps/s of three runs of `run` (which returns its step count): wall, CPU."""
    wall, cpu = [], []
    for _ in range(3):
        start, start_cpu = time.perf_counter(), time.process_time()
        steps = run()
        wall.append(steps / (time.perf_counter() - start))
        cpu.append(steps / max(time.process_time() - start_cpu, 1e-9))
    return max(wall), max(cpu)


def packed_env(robots: int, max_steps: int, **options: Any) -> SwarmVectorEnv:
    """A 2x2 shape in a wide arena, its robots starting in one square block round the centre."""
    grid = np.ones((2, 2), dtype=bool)
    side = int(np.sqrt(robots)) * 2 + 10
    warnings.simplefilter("ignore", ShapeWarning)  # far more robots than cells, on purpose
    free = vector_env(grid, agents=robots, arena=(side, side)).episode.world.start_cells()
    block = free[np.argsort(np.abs(free - side // 2).max(axis=1), kind="stable")[:robots]]
    with tempfile.TemporaryDirectory() as folder:
        start = os.path.join(folder, "start.csv")
        np.savetxt(start, block, fmt="%d", delimiter=",", header="x,y", comments="")
        return vector_env(
            grid, agents=robots, arena=(side, side), start=start, max_steps=max_steps, **options
        )


def batched_on_disc(robots: int, steps: int) -> tuple[SwarmVectorEnv, np.ndarray]:
    """The batched environment on a disc of `robots` cells, and `steps` rows of random moves."""
    vec = vector_env(disc(robots), max_steps=steps + 1)
    return vec, np.random.default_rng(0).integers(0, 5, (steps, vec.num_envs))


def stepped(vec: SwarmVectorEnv, moves: np.ndarray) -> Callable[[], int]:
    """A run of `vec` through `moves` from its first step, to time."""

    def run() -> int:
        vec.reset(seed=1)
        for row in moves:
            vec.step(row)
        return len(moves)

    return run


def batched_rate(robots: int = 1000, steps: int = 300) -> tuple[float, float]:
    """The batched interface's best steps/s (wall, CPU): the figure issue 32 holds to 1,500."""
    return timed(stepped(*batched_on_disc(robots, steps)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=300)
    args = parser.parse_args()
    shape = disc(args.robots)
    vec, moves = batched_on_disc(args.robots, args.steps)

    def simulator() -> int:
        vec.reset(seed=1)
        episode = vec.episode
        for row in moves:
            episode.relay.give(row, np.zeros((len(row), 0), dtype=np.int64))
            episode.swarm.step()
            episode.control.look()
        return len(moves)

    packed = packed_env(args.robots, args.steps + 1)

    par = parallel_env(shape, max_steps=args.steps + 1)
    agents = par.possible_agents

    def per_agent() -> int:
        par.reset(seed=1)
        for row in moves[:50]:
            par.step(dict(zip(agents, row.tolist(), strict=True)))
        return 50

    vec.reset(seed=1)
    entries = len(vec.episode.control.sensed.owner)
    print(
        f"learning environment, {vec.num_envs:,} robots, {vec.layout.size} numbers per "
        f"observation, {entries:,} neighbour entries at the start; steps/s, best of 3"
    )
    rows = [
        ("batched (vector_env)", timed(stepped(vec, moves)), TARGET),
        ("simulator alone (sense + step)", timed(simulator), None),
        ("batched, robots packed", timed(stepped(packed, moves)), None),
        ("PettingZoo dicts (parallel_env)", timed(per_agent), None),
    ]
    central = max(stepping(disc(args.robots), 50)["steps_per_s"] for _ in range(3))
    for name, (wall, cpu), goal in rows:
        met = goal is not None and wall >= goal
        verdict = "" if goal is None else f"   target >= {goal}: {'met' if met else 'MISSED'}"
        print(f"  {name:34s} wall {wall:7.0f}   cpu {cpu:7.0f}{verdict}")
    print(f"  for scale: bench.py's stepping, steps/s wall {central:7.0f}   (the README's table)")
    print(f"load average now: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()

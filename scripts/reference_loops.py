"""A swarm stepped the way one would write it without swarmshape: a pygame sprite loop and a
Mesa 3 model, for `bench.py`'s side-by-side rows (issue 32).

    .venv/bin/python scripts/reference_loops.py {sprites,mesa} SCENARIO.npz [--steps 20]

Prints ``{"steps": ..., "seconds": ...}``: the seconds the steps took, set-up excluded (the
whole process, imports and set-up included, is what `bench.py` times from the shell: with the
targets given, not worked out). Mesa is an extra: ``pip install -e '.[bench]'``.

`bench.py` writes the scenario (`SCENARIO.npz`: the arena's `size`, each robot's `start` and
`goal` cell) from its `stepping` row's 1,000-robot block, so the robots, their start cells and
their targets are that run's; this file imports nothing of swarmshape. At each step
every robot, in a fresh random order, moves one cell toward its target (along x while it
differs, then along y) if no robot stands there. That is less than a swarmshape step does (no
planning, no acceleration, whole cells), and robots may block one another for good: these
loops measure what a step of the same swarm costs, not how well it forms. Nothing is drawn,
as in a headless swarmshape run. The sprite loop tests each move against every sprite
(`spritecollideany`), so its step grows as the square of the robots; Mesa's grid looks the
cell up.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import numpy as np

SEED = 1


def load(scenario: Path) -> tuple[tuple[int, int], np.ndarray, np.ndarray]:
    """The arena's size, and each robot's start and target cells ``(n, 2)``."""
    with np.load(scenario) as saved:
        width, height = saved["size"].tolist()
        return (width, height), saved["start"], saved["goal"]


def toward(cell: tuple[int, int], goal: tuple[int, int]) -> tuple[int, int] | None:
    """The next cell from `cell` toward `goal`: along x first, then along y (None: there)."""
    (x, y), (gx, gy) = cell, goal
    if x != gx:
        return x + (1 if gx > x else -1), y
    if y != gy:
        return x, y + (1 if gy > y else -1)
    return None


def sprites(scenario: Path, steps: int) -> tuple[float, np.ndarray]:
    """The robots as pygame sprites of one cell, a probe sprite testing the next cell against
    the group (`spritecollideany`), as pygame's sprite tutorials do: the seconds the steps
    took, and where the robots stand after them."""
    import pygame

    _, starts, goals = load(scenario)
    rng = np.random.default_rng(SEED)

    class Robot(pygame.sprite.Sprite):
        def __init__(self, cell: np.ndarray, goal: np.ndarray) -> None:
            super().__init__()
            self.rect = pygame.Rect(int(cell[0]), int(cell[1]), 1, 1)
            self.goal = (int(goal[0]), int(goal[1]))

        def update(self, robots: pygame.sprite.Group, probe: pygame.sprite.Sprite) -> None:
            cell = toward(self.rect.topleft, self.goal)
            if cell is None:
                return
            probe.rect = pygame.Rect(cell, (1, 1))
            if pygame.sprite.spritecollideany(probe, robots) is None:
                self.rect = probe.rect

    robots = [Robot(cell, goal) for cell, goal in zip(starts, goals, strict=True)]
    group = pygame.sprite.Group(robots)
    probe = pygame.sprite.Sprite()
    started = time.perf_counter()
    for _ in range(steps):
        for index in rng.permutation(len(robots)).tolist():
            robots[index].update(group, probe)
    return time.perf_counter() - started, np.array([robot.rect.topleft for robot in robots])


def mesa(scenario: Path, steps: int) -> tuple[float, np.ndarray]:
    """The robots as Mesa 3 agents on a `SingleGrid` (one agent a cell), stepped in a random
    order by `shuffle_do`, as Mesa's tutorials do; returns as `sprites` does."""
    import mesa as mesa3

    size, starts, goals = load(scenario)

    class Robot(mesa3.Agent):
        def __init__(self, model: mesa3.Model, goal: np.ndarray) -> None:
            super().__init__(model)
            self.goal = (int(goal[0]), int(goal[1]))

        def step(self) -> None:
            cell = toward(self.pos, self.goal)
            if cell is not None and self.model.grid.is_cell_empty(cell):
                self.model.grid.move_agent(self, cell)

    class Block(mesa3.Model):
        def __init__(self) -> None:
            super().__init__(seed=SEED)
            self.grid = mesa3.space.SingleGrid(*size, torus=False)
            self.robots = [Robot(self, goal) for goal in goals]
            for robot, cell in zip(self.robots, starts, strict=True):
                self.grid.place_agent(robot, (int(cell[0]), int(cell[1])))

        def step(self) -> None:
            self.agents.shuffle_do("step")

    model = Block()
    started = time.perf_counter()
    for _ in range(steps):
        model.step()
    return time.perf_counter() - started, np.array([robot.pos for robot in model.robots])


LOOPS = {"sprites": sprites, "mesa": mesa}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("loop", choices=sorted(LOOPS))
    parser.add_argument("scenario", type=Path)
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    try:
        seconds, _ = LOOPS[args.loop](args.scenario, args.steps)
    except (OSError, ValueError, KeyError) as bad:  # no file, not an .npz, a field missing
        parser.exit(2, f"reference_loops.py: error: {args.scenario}: not a scenario ({bad})\n")
    print(json.dumps({"steps": args.steps, "seconds": round(seconds, 4)}))


if __name__ == "__main__":
    main()

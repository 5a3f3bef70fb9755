"""The task suite ``shape-formation-v1``: named tasks, each a shipped shape, a robot count, a
start layout, sensing noise and an episode length, with every physical setting pinned here so
that a later change of swarmshape's defaults cannot change a task. A task's episodes are
decided by (task, seed) alone: two papers that name ``star-1k`` and seed 2 mean the same
robots starting on the same cells, the same noise and the same claims resolved the same way
(for a given swarmshape release; a change to the simulator's physics makes a new version of
the suite, never a silent change to this one).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from swarmshape.config import bundled_shapes
from swarmshape.env.vector import SwarmVectorEnv, vector_env
from swarmshape.errors import InputError

SUITE = "shape-formation-v1"

PHYSICS = {
    "max_speed": 0.5,
    "max_accel": 0.125,
    "speed_variation": 0.0,
    "sense_radius": 3.0,
    "failure_rate": 0.0,
}
"""What every task of this version shares: the simulator's defaults when it was fixed."""


@dataclass(frozen=True)
class Task:
    """One task of the suite: the world and how long an episode lasts."""

    name: str
    shape: str
    """A shipped shape (``shapes/`` in the source, ``swarmshape/shapes`` when installed)."""
    robots: int
    """Robots in the swarm; the shape is sized to them (as many cells, or just fewer)."""
    steps: int
    """Episode length: an episode not formed by then is truncated (a failure)."""
    seeds: tuple[int, ...]
    """The seeds the leaderboard evaluates."""
    start: str = "scatter"
    """scatter: random free cells; packed: a block against the seeds."""
    distance_noise: float = 0.0
    msg_loss: float = 0.0

    def options(self) -> dict[str, Any]:
        """The environment's options for this task (all but messages)."""
        return {
            "agents": self.robots,
            "fit": "agents",
            "start": self.start,
            "max_steps": self.steps,
            "distance_noise": self.distance_noise,
            "msg_loss": self.msg_loss,
            **PHYSICS,
        }

    def env(
        self, message_size: int = 0, message_range: tuple[int, int] = (0, 255)
    ) -> SwarmVectorEnv:
        """The batched environment of this task, with the policy's broadcasts (they change
        what robots observe, never where they go)."""
        return vector_env(
            bundled_shapes() / self.shape,
            message_size=message_size,
            message_range=message_range,
            **self.options(),
        )

    def described(self) -> dict[str, Any]:
        """The task as plain values (for results files)."""
        return {
            "shape": self.shape,
            "robots": self.robots,
            "start": self.start,
            "distance_noise": self.distance_noise,
            "msg_loss": self.msg_loss,
            "steps": self.steps,
        }


SMALL, MEDIUM, LARGE = tuple(range(10)), tuple(range(3)), (0,)

TASKS: dict[str, Task] = {
    task.name: task
    for task in (
        Task("star-100", "star.png", 100, 1_000, SMALL),
        Task("ring-100", "ring.png", 100, 1_000, SMALL),
        Task("horse-100", "horse.png", 100, 1_000, SMALL),
        Task("star-100-packed", "star.png", 100, 1_000, SMALL, start="packed"),
        Task("star-100-noisy", "star.png", 100, 1_000, SMALL, distance_noise=0.1, msg_loss=0.1),
        Task("star-1k", "star.png", 1_000, 2_000, MEDIUM),
        Task("horse-1k", "horse.png", 1_000, 2_000, MEDIUM),
        Task("star-10k", "star.png", 10_000, 2_000, LARGE),
    )
}
"""``shape-formation-v1``: five tasks at 100 robots (ten seeds each), two at 1,000 (three
seeds) and one at 10,000 (one seed, an episode capped at 2,000 steps, about seven times
the makespan bound: one such episode took 8 to 48 minutes on this project's shared 2-core
machine, depending on the policy)."""


def tasks(names: str | list[str] | None = None) -> list[Task]:
    """The tasks named (a list, or one comma-separated string), in the suite's order if None."""
    if names is None:
        return list(TASKS.values())
    if isinstance(names, str):
        names = [name.strip() for name in names.split(",") if name.strip()]
    unknown = [name for name in names if name not in TASKS]
    if unknown or not names:
        raise InputError(
            f"unknown task {unknown[0]!r} in {SUITE}; choose from {', '.join(TASKS)}"
            if unknown
            else f"no task named; choose from {', '.join(TASKS)}"
        )
    return [TASKS[name] for name in names]


def table(chosen: list[Task] | None = None) -> str:
    """The suite's tasks as a Markdown table (docs/benchmark.md shows this one)."""
    rows = [
        "| task | shape | robots | start | distance noise | message loss | steps | seeds |",
        "| --- | --- | ---: | --- | ---: | ---: | ---: | --- |",
    ]
    for task in chosen or TASKS.values():
        seeds = f"{task.seeds[0]}-{task.seeds[-1]}" if len(task.seeds) > 1 else str(task.seeds[0])
        rows.append(
            f"| {task.name} | {task.shape} | {task.robots:,} | {task.start} | "
            f"{task.distance_noise:g} | {task.msg_loss:g} | {task.steps:,} | {seeds} |"
        )
    return "\n".join(rows) + "\n"

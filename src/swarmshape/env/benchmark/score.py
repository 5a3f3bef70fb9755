"""Scoring: `evaluate` runs any policy on tasks and seeds and gives, per task, what the
leaderboard shows; `to_json` and `to_markdown` write it the same way byte for byte whenever
the episodes are the same.

A policy is any callable from every robot's observations ``(n, size)`` to their actions
(``(n,)`` moves, or ``(n, 1 + message_size)`` rows of a move and a broadcast). It may also have

- ``name``: how results name it (default: its class's name);
- ``message_size`` and ``message_range``: the integers each robot broadcasts (default none);
- ``reset(context)``: called before every episode with a `Context` (what a policy with state,
  or with its own randomness, needs: the layout of observations, the shape as the robots know
  it, the number of robots, and a generator seeded from the episode).

The policy sees observations only; the figures are read from the swarm afterwards.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from swarmshape.core.metrics import run_metrics
from swarmshape.core.perception import Blueprint
from swarmshape.env.benchmark.suite import SUITE, Task
from swarmshape.env.observe import Layout
from swarmshape.errors import InputError

DIGITS = 6


class Policy(Protocol):
    def __call__(self, obs: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class Context:
    """What a policy is told before an episode."""

    task: Task
    seed: int
    robots: int
    layout: Layout
    """Where each value sits in an observation row."""
    blueprint: Blueprint
    """The shape in its seed frame, as every robot knows it from the start."""

    def rng(self) -> np.random.Generator:
        """The policy's own generator for this episode: the same for the same seed, and
        independent of the environment's (seeded with `seed` alone)."""
        return np.random.default_rng([self.seed, 1])


def name_of(policy: Any) -> str:
    return str(getattr(policy, "name", type(policy).__name__))


def play(policy: Policy, task: Task, seed: int, env: Any) -> Iterator[bool]:
    """Run one episode of `policy` on `task` from `seed` in `env`, yielding after every step
    whether the shape is formed (a caller reads `env` as the swarm forms, or stops early)."""
    obs, _ = env.reset(seed=seed)
    if hasattr(policy, "reset"):
        policy.reset(Context(task, seed, env.num_envs, env.layout, env.blueprint))
    while True:
        actions = np.asarray(policy(obs))
        try:
            env.episode.split(actions)
        except ValueError as error:
            raise InputError(f"policy {name_of(policy)}: {error}") from None
        obs, _, terminated, truncated, _ = env.step(actions)
        yield bool(terminated[0])
        if terminated[0] or truncated[0]:
            return


def episode(policy: Policy, task: Task, seed: int, env: Any = None) -> dict[str, Any]:
    """One episode of `policy` on `task` from `seed`: its figures (see `evaluate`)."""
    env = env or environment(policy, task)
    for _ in play(policy, task, seed, env):
        pass
    swarm = env.episode.swarm
    figures = run_metrics(swarm)
    return {
        "seed": seed,
        "formed": figures["steps"] is not None,
        "coverage": figures["coverage"],
        "steps_to_form": figures["steps"],
        "steps_run": swarm.step_count,
        "makespan_lower_bound": figures["makespan_lower_bound"],
        "makespan_ratio": figures["makespan_ratio"],
        "distance_ratio": figures["distance_ratio"],
        "claims_refused": swarm.driver.refused,
        "messages": figures["messages"],
    }


def environment(policy: Any, task: Task) -> Any:
    """The task's environment with the policy's broadcasts."""
    size = int(getattr(policy, "message_size", 0))
    return task.env(size, tuple(getattr(policy, "message_range", (0, 255))))


def evaluate(
    policy: Policy,
    tasks: list[Task],
    seeds: list[int] | None = None,
    progress: Any = None,
) -> dict[str, Any]:
    """`policy` on every task, on `seeds` (None: each task's own), as plain values:

    per task, its definition, its episodes' figures, and over them the ``success_rate``
    (episodes formed before the step limit), the mean ``coverage`` at the end (and the
    least), the mean ``steps_to_form`` and ``makespan_ratio`` (steps over the makespan lower
    bound) and ``distance_ratio`` (distance travelled over the least total distance of any
    assignment) over the episodes that formed (None if none did), and the mean
    ``claims_refused`` (moves into a taken cell, or lost to another robot's claim) and
    ``messages`` (broadcasts sent) per episode. `progress`, if given, is called with each
    task's name and wall-clock seconds (they are not part of the results)."""
    results: dict[str, Any] = {"suite": SUITE, "policy": name_of(policy), "tasks": {}}
    for task in tasks:
        started = time.perf_counter()
        env = environment(policy, task)
        runs = [
            episode(policy, task, seed, env) for seed in (task.seeds if seeds is None else seeds)
        ]
        env.close()
        results["tasks"][task.name] = {**task.described(), **summary(runs), "episodes": runs}
        if progress is not None:
            progress(task.name, time.perf_counter() - started)
    return results


def summary(runs: list[dict[str, Any]]) -> dict[str, Any]:
    formed = [run for run in runs if run["formed"]]

    def mean(values: list[float]) -> float | None:
        return round(float(np.mean(values)), DIGITS) if values else None

    return {
        "seeds": [run["seed"] for run in runs],
        "success_rate": mean([float(run["formed"]) for run in runs]),
        "coverage": mean([run["coverage"] for run in runs]),
        "coverage_least": min(run["coverage"] for run in runs),
        "steps_to_form": mean([run["steps_to_form"] for run in formed]),
        "makespan_ratio": mean([run["makespan_ratio"] for run in formed]),
        "distance_ratio": mean([run["distance_ratio"] for run in formed]),
        "claims_refused": mean([run["claims_refused"] for run in runs]),
        "messages": mean([run["messages"] for run in runs]),
    }


def to_json(results: dict[str, Any]) -> str:
    """The results as JSON text: the same results, the same bytes."""
    return json.dumps(results, indent=2, allow_nan=False) + "\n"


COLUMNS = ("task", "robots", "episodes", "success", "coverage (least)", "steps to form",
           "x makespan bound", "x least distance", "claims refused", "messages")  # fmt: skip


def to_markdown(results: dict[str, Any]) -> str:
    """The results as a Markdown table, one row per task."""
    rows = [
        f"{SUITE}, policy {results['policy']}:",
        "",
        "| " + " | ".join(COLUMNS) + " |",
        "| --- |" + " ---: |" * (len(COLUMNS) - 1),
    ]
    for name, task in results["tasks"].items():
        cells = [
            name,
            f"{task['robots']:,}",
            str(len(task["episodes"])),
            f"{task['success_rate']:.0%}",
            f"{task['coverage']:.1%} ({task['coverage_least']:.1%})",
            _number(task["steps_to_form"], "{:,.0f}"),
            _number(task["makespan_ratio"], "{:.1f}x"),
            _number(task["distance_ratio"], "{:.2f}x"),
            f"{task['claims_refused']:,.0f}",
            f"{task['messages']:,.0f}",
        ]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def _number(value: float | None, form: str) -> str:
    return "-" if value is None else form.format(value)


def leaderboard(rows: list[dict[str, Any]]) -> str:
    """Policies side by side (one results dict each, over the same tasks): the mean coverage
    at the end of each task, and its success rate."""
    names = list(rows[0]["tasks"])
    lines = ["| policy | " + " | ".join(names) + " |", "| --- |" + " ---: |" * len(names)]
    for results in rows:
        cells = []
        for name in names:
            task = results["tasks"].get(name)
            cells.append(
                "" if task is None else f"{task['coverage']:.1%} ({task['success_rate']:.0%})"
            )
        lines.append(f"| {results['policy']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"

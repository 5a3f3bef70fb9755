"""The leaderboard's baselines, and how a policy is named: ``random``, ``learned``, any local
program by its registered name (driven through the environment), or a policy in code,
``path/to/file.py:Name`` or ``package.module:Name`` (a class, made with no arguments, or a
ready policy object)."""

from __future__ import annotations

from typing import Any

import numpy as np

import swarmshape.strategies as strategies
from swarmshape.core.local import Memory, Program
from swarmshape.env.benchmark.learned import Learned
from swarmshape.env.episode import MOVES
from swarmshape.env.observe import perception_of
from swarmshape.errors import InputError


class Random:
    """Every robot picks one of the five moves at random, every step."""

    name = "random"

    def reset(self, context: Any) -> None:
        self.rng = context.rng()

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return self.rng.integers(0, MOVES, len(obs))


class Scripted:
    """A local program as a policy: it rebuilds each step's `Perception` from the observations
    alone (`perception_of`) and acts with its own memory and its own generator, as
    ``examples/learn_scripted.py`` shows. Its broadcasts may take any value a float32
    observation holds exactly."""

    message_range = (-(2**24), 2**24 - 1)

    def __init__(self, program: str) -> None:
        self.program: Program = strategies.create(program)
        self.name = program
        self.message_size = self.program.message_size

    def reset(self, context: Any) -> None:
        self.layout, self.blueprint = context.layout, context.blueprint
        self.memory = Memory(self.program.memory, context.robots)
        self.rng = context.rng()

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        sense = perception_of(obs, self.layout, self.blueprint)
        moves, messages = self.program.act(sense, self.memory, self.rng)
        return np.column_stack([moves, messages]) if self.message_size else moves


def local_programs() -> list[str]:
    """Every registered or installed local program, by name."""
    return sorted(name for name, cls in strategies.available().items() if cls.kind == "local")


def policy(spec: str) -> Any:
    """The policy `spec` names (see the module's description)."""
    if spec == "random":
        return Random()
    if spec == "learned":
        return Learned()
    if not strategies.is_code(spec):
        if spec in local_programs():
            return Scripted(spec)
        choices = ", ".join(["random", "learned", *local_programs()])
        raise InputError(f"unknown policy {spec!r}; choose {choices}, or file.py:Name")
    found = strategies.load(spec, "policy")
    made = found() if isinstance(found, type) else found
    if not callable(made):
        raise InputError(f"policy {spec!r} is not callable (observations -> actions)")
    if not hasattr(made, "name"):
        made.name = spec.rpartition(":")[2]
    return made

"""Strategies that assign every target at once and let all agents move together.

Each differs only in how it matches agents to targets (see `swarmshape.assignment`); the core
moves everyone concurrently and passes walled-in targets inward by swapping.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from swarmshape import assignment
from swarmshape.assignment import Matcher
from swarmshape.strategies import register

if TYPE_CHECKING:
    from swarmshape.swarm import Swarm


class OneShot:
    """Base for strategies that match each group's agents to its targets once, at the start."""

    concurrent: ClassVar[bool] = True
    match: ClassVar[Matcher]

    def start(self, swarm: Swarm) -> None:
        for group in range(len(swarm.world.groups)):
            agents = np.flatnonzero(swarm.group == group)
            targets = np.flatnonzero(swarm.world.target_group == group)
            chosen = type(self).match(
                swarm.cell[agents].astype(np.float64),
                swarm.world.targets[targets].astype(np.float64),
                swarm.rng,
            )
            swarm.assign(agents[chosen], targets)

    def on_settled(self, swarm: Swarm, agents: np.ndarray) -> None:
        """Nothing to hand on: every target was assigned at the start."""

    def on_reshape(self, swarm: Swarm, group: int) -> None:
        """The shape changed: match the idle agents to the open cells the same way."""
        swarm.recruit(group, type(self).match)


@register
class Optimal(OneShot):
    name: ClassVar[str] = "optimal"
    description: ClassVar[str] = (
        "least total squared distance (CAPT); exact to 1,500 agents, bisection above"
    )
    match = staticmethod(assignment.optimal)


@register
class Greedy(OneShot):
    name: ClassVar[str] = "greedy"
    description: ClassVar[str] = "each target takes its nearest free agent"
    match = staticmethod(assignment.greedy)


@register
class Random(OneShot):
    name: ClassVar[str] = "random"
    description: ClassVar[str] = "a random agent for each target: the worst-case baseline"
    match = staticmethod(assignment.random_assignment)

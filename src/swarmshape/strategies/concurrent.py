"""Strategies that assign every target at once and let all robots move together.

Each differs only in how it matches robots to targets (see `swarmshape.core.assignment`); the
core moves everyone at once and passes walled-in targets inward by swapping (`Motion.SWAP`).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from swarmshape.core import assignment
from swarmshape.core.assignment import Matcher
from swarmshape.core.steering import Strategy, SwarmView
from swarmshape.strategies import register


class OneShot(Strategy):
    """Base for strategies that match each group's robots to its targets once, at the start."""

    match: ClassVar[Matcher]

    def on_start(self, swarm: SwarmView) -> None:
        for group in range(len(swarm.world.groups)):
            robots = np.flatnonzero(swarm.group == group)
            targets = np.flatnonzero(swarm.target_group == group)
            chosen = type(self).match(
                swarm.cells[robots].astype(np.float64),
                swarm.targets[targets].astype(np.float64),
                swarm.rng,
            )
            swarm.assign(robots[chosen], targets)

    def on_reshape(self, swarm: SwarmView, group: int) -> None:
        """The shape changed: match the idle robots to the open cells the same way."""
        swarm.recruit(group, type(self).match)


@register
class Optimal(OneShot):
    name: ClassVar[str] = "optimal"
    description: ClassVar[str] = (
        "least total squared distance (CAPT); exact to 1,500 robots, bisection above"
    )
    match = staticmethod(assignment.optimal)


@register
class Greedy(OneShot):
    name: ClassVar[str] = "greedy"
    description: ClassVar[str] = "each target takes its nearest free robot"
    match = staticmethod(assignment.greedy)


@register
class Random(OneShot):
    name: ClassVar[str] = "random"
    description: ClassVar[str] = "a random robot for each target: the worst-case baseline"
    match = staticmethod(assignment.random_assignment)

"""Strategies that match every robot to a target at the start and let many move together.

Each differs only in how it matches robots to targets (see `swarmshape.core.assignment`). All
send robots off deepest target first: a robot whose target lies `STAGGER` levels shallower
(cells nearer the shape's edge) leaves that many steps later, so the rim does not fill while
robots still have to pass through it (on a 10,000-cell disc this cut the steps to form by a
quarter). The core moves everyone at once and passes walled-in targets inward by swapping
(`Motion.SWAP`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from swarmshape.core import assignment
from swarmshape.core.assignment import Matcher
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.steering import Strategy, SwarmView
from swarmshape.strategies import register

STAGGER = 1.0
"""Steps a robot waits per level of depth its target lies above the group's deepest."""


class OneShot(Strategy):
    """Base for strategies that match each group's robots to its targets once, at the start,
    and send them off deepest target first."""

    match: ClassVar[Matcher]

    def __init__(self, options: Any = None) -> None:
        super().__init__(options)
        self._planned = np.zeros(0, dtype=np.int64)
        """Each robot's target, until it is sent off (-1: sent, or none)."""
        self._leaves_at = np.zeros(0, dtype=np.int64)
        """The step at which each robot is sent off to its planned target."""

    def on_start(self, swarm: SwarmView) -> None:
        self._planned = np.full(len(swarm.cells), -1, dtype=np.int64)
        for group in range(len(swarm.world.groups)):
            robots = np.flatnonzero(swarm.group == group)
            targets = np.flatnonzero(swarm.target_group == group)
            chosen = type(self).match(
                swarm.cells[robots].astype(np.float64),
                swarm.targets[targets].astype(np.float64),
                swarm.rng,
            )
            self._planned[robots[chosen]] = targets
        depth = swarm.world.depth()
        deepest = np.zeros(len(swarm.world.groups), dtype=np.int64)
        np.maximum.at(deepest, swarm.target_group, depth)
        planned = np.maximum(self._planned, 0)
        wait = STAGGER * (deepest[swarm.target_group[planned]] - depth[planned])
        self._leaves_at = np.floor(wait).astype(np.int64)
        self.on_step(swarm)

    def on_step(self, swarm: SwarmView) -> None:
        """Send off the robots whose time has come."""
        due = np.flatnonzero((self._planned >= 0) & (self._leaves_at <= swarm.step))
        if len(due):
            swarm.assign(due, self._planned[due])
            self._planned[due] = -1

    def on_reshape(self, swarm: SwarmView, group: int) -> None:
        """The shape changed: match the idle robots (those not yet sent off among them) to the
        open cells the same way."""
        self._planned[swarm.group == group] = -1
        swarm.recruit(group, type(self).match)

    def restore(self, saved: Snapshot, swarm: SwarmView) -> None:
        """Take the plans back, checked: one per robot, each -1 or a target of its group."""
        super().restore(saved, swarm)
        n, m = len(swarm.cells), len(swarm.targets)
        planned, leaves = self._planned, self._leaves_at
        if planned.shape != (n,) or leaves.shape != (n,) or not _whole(planned, leaves):
            raise saved.error("_planned", f"does not hold one whole number per robot ({n})")
        sent = planned >= 0
        if (planned < -1).any() or (planned >= m).any():
            raise saved.error("_planned", "names a target that does not exist")
        if (swarm.target_group[planned[sent]] != swarm.group[sent]).any():
            raise saved.error("_planned", "sends a robot to another group's target")

    def on_renumber(self, swarm: SwarmView, renumber: np.ndarray) -> None:
        """Robots not yet sent off keep their planned cells, under the cells' new indices
        (another group re-formed smaller shifted them: two-squares.toml, seed 5, crashed)."""
        planned = self._planned >= 0
        self._planned[planned] = renumber[self._planned[planned]]

    def on_hand_over(self, swarm: SwarmView, movers: np.ndarray, idle: np.ndarray) -> None:
        """The movers wait in the idle robots' places, so they leave when and where those would
        have (under the 10,000-robot disc's plan, an idle robot sent on without this was sent
        its own cell later too, and its mover never: the disc stopped 4 cells short)."""
        for plan in (self._planned, self._leaves_at):
            plan[movers], plan[idle] = plan[idle], plan[movers]

    def on_fault(self, swarm: SwarmView, group: int, robots: np.ndarray) -> None:
        """A fault opened cells: the idle robots (those not yet sent off among them) are matched
        to the open cells the same way, as after a reshape."""
        self.on_reshape(swarm, group)


def _whole(*arrays: np.ndarray) -> bool:
    return all(array.dtype.kind == "i" for array in arrays)


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

"""The paper's strategy: one robot of each group moves at a time, passing the baton by message.

The seeds send the first "go to target T" message to a random waiting robot. Whenever a robot
settles it sends the next target of the fill order to another waiting robot, chosen at random.
When a group's shape is complete its remaining robots wander (the core sees to that).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from swarmshape.core.messages import SEEDS
from swarmshape.core.motion import Motion
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import MOVING, WANDERING
from swarmshape.core.steering import Strategy, SwarmView
from swarmshape.strategies import register
from swarmshape.strategies.fill_order import DEFAULT_ORDER, ORDERS, fill_sequence


@register
class Paper(Strategy):
    name: ClassVar[str] = "paper"
    motion: ClassVar[Motion] = Motion.ROUTE
    description: ClassVar[str] = "one mover per group at a time, targets handed on by message"

    def __init__(self, order: str = DEFAULT_ORDER) -> None:
        self.order = order
        self._sequence: list[np.ndarray] = []
        self._next: list[int] = []

    def on_start(self, swarm: SwarmView) -> None:
        self._order_open_targets(swarm)
        for g in range(len(swarm.world.groups)):
            self._hand_on(swarm, g, SEEDS)

    def on_reshape(self, swarm: SwarmView, group: int) -> None:
        """Order the open cells anew; the seeds restart the chain if nobody is moving."""
        self._order_open_targets(swarm)
        moving = (swarm.group == group) & (swarm.state == MOVING)
        told = [m for m in swarm.pending if swarm.group[m.recipient] == group]
        if not moving.any() and not told:
            self._hand_on(swarm, group, SEEDS)

    def _order_open_targets(self, swarm: SwarmView) -> None:
        """Each group's fill order, as target indices, without the cells already taken."""
        world = swarm.world
        first = np.cumsum([0] + [len(g.targets) for g in world.groups])
        taken = np.zeros(len(world.targets), dtype=bool)
        taken[swarm.target[swarm.target >= 0]] = True
        taken[[m.target for m in swarm.pending]] = True
        self._sequence = []
        for g in range(len(world.groups)):
            sequence = first[g] + fill_sequence(world, g, self.order, swarm.rng)
            self._sequence.append(sequence[~taken[sequence]])
        self._next = [0] * len(world.groups)

    def restore(self, saved: Snapshot, swarm: SwarmView) -> None:
        """Take the saved fill orders back, checked against the world they order."""
        super().restore(saved, swarm)
        groups, targets = len(swarm.world.groups), len(swarm.targets)
        if self.order not in ORDERS:
            raise saved.error("order", f"is {self.order!r}, not one of {', '.join(ORDERS)}")
        if len(self._sequence) != groups or len(self._next) != groups:
            raise saved.error("_sequence", f"does not have one order per group ({groups})")
        for sequence, done in zip(self._sequence, self._next, strict=True):
            if not isinstance(sequence, np.ndarray) or sequence.ndim != 1:
                raise saved.error("_sequence", "holds something other than lists of targets")
            in_range = sequence.dtype.kind == "i" and ((sequence >= 0) & (sequence < targets)).all()
            counted = type(done) is int and 0 <= done <= len(sequence)
            if sequence.ndim != 1 or not in_range or not counted:
                raise saved.error("_sequence", "names targets that do not exist")

    def on_settled(self, swarm: SwarmView, agents: np.ndarray) -> None:
        for agent in agents.tolist():
            self._hand_on(swarm, int(swarm.group[agent]), agent)

    def _hand_on(self, swarm: SwarmView, group: int, sender: int) -> None:
        """Send the group's next target to a random waiting robot, while targets remain.

        Once a shape was complete its spare robots wander; a changed shape recruits them.
        """
        idle = swarm.waiting(group)
        if len(idle) == 0:
            idle = np.flatnonzero((swarm.group == group) & (swarm.state == WANDERING))
        if self._next[group] == len(self._sequence[group]) or len(idle) == 0:
            return
        recipient = int(swarm.rng.choice(idle))
        swarm.send(sender, recipient, int(self._sequence[group][self._next[group]]))
        self._next[group] += 1

"""The paper's strategy: one robot of each group moves at a time, passing the baton by message.

The seeds send the first "go to target T" message to a random waiting robot. Whenever a robot
settles it sends the next target of the fill order to another waiting robot, chosen at random.
When a group's shape is complete its remaining robots wander (the core sees to that).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np

from swarmshape.fill_order import fill_sequence
from swarmshape.messages import SEEDS
from swarmshape.strategies import register
from swarmshape.swarm import MOVING, WANDERING

if TYPE_CHECKING:
    from swarmshape.swarm import Swarm


@register
class Paper:
    name: ClassVar[str] = "paper"
    concurrent: ClassVar[bool] = False
    description: ClassVar[str] = "one mover per group at a time, targets handed on by message"

    def __init__(self, order: str = "outward") -> None:
        self.order = order
        self._sequence: list[np.ndarray] = []
        self._next: list[int] = []

    def start(self, swarm: Swarm) -> None:
        self._order_open_targets(swarm)
        for g in range(len(swarm.world.groups)):
            self._hand_on(swarm, g, SEEDS)

    def on_reshape(self, swarm: Swarm, group: int) -> None:
        """Order the open cells anew; the seeds restart the chain if nobody is moving."""
        self._order_open_targets(swarm)
        moving = (swarm.group == group) & (swarm.state == MOVING)
        told = [m for m in swarm.queue.pending if swarm.group[m.recipient] == group]
        if not moving.any() and not told:
            self._hand_on(swarm, group, SEEDS)

    def _order_open_targets(self, swarm: Swarm) -> None:
        """Each group's fill order, as target indices, without the cells already taken."""
        world = swarm.world
        first = np.cumsum([0] + [len(g.targets) for g in world.groups])
        taken = np.zeros(len(world.targets), dtype=bool)
        taken[swarm.target[swarm.target >= 0]] = True
        taken[[m.target for m in swarm.queue.pending]] = True
        self._sequence = []
        for g in range(len(world.groups)):
            sequence = first[g] + fill_sequence(world, g, self.order, swarm.rng)
            self._sequence.append(sequence[~taken[sequence]])
        self._next = [0] * len(world.groups)

    def on_settled(self, swarm: Swarm, agents: np.ndarray) -> None:
        for agent in agents.tolist():
            self._hand_on(swarm, int(swarm.group[agent]), agent)

    def _hand_on(self, swarm: Swarm, group: int, sender: int) -> None:
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

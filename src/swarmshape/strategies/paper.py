"""The paper's strategy: one robot of each group moves at a time, passing the baton by message.

The seeds send the first "go to target T" message to a random waiting robot. Whenever a robot
settles it sends the next target of the fill order to another waiting robot, chosen at random.
When a group's shape is complete its remaining robots wander (the core sees to that).

After a fault the chain restarts from a settled neighbour of the gap and the group repairs,
still one mover at a time: each hand-on sends the first open cell (in fill order) that an idle
robot can reach to such a robot; when every open cell is walled in by settled robots, the
settled neighbour of a gap nearest the free space moves into it, which moves the gap one cell
outward, until it can be reached.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy

from swarmshape.core.messages import SEEDS
from swarmshape.core.motion import STEPS, Motion
from swarmshape.core.options import option
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import LOST, MOVING, SETTLED, WANDERING
from swarmshape.core.steering import Strategy, SwarmView
from swarmshape.strategies import register
from swarmshape.strategies.fill_order import DEFAULT_ORDER, ORDERS, fill_sequence


@register
class Paper(Strategy):
    name: ClassVar[str] = "paper"
    motion: ClassVar[Motion] = Motion.ROUTE
    description: ClassVar[str] = "one mover per group at a time, targets handed on by message"

    @dataclass(frozen=True)
    class Options:
        order: str = option(
            DEFAULT_ORDER,
            "the target function: outward from the seeds, left-to-right, or random",
            choices=ORDERS,
        )

    def __init__(self, options: Options | None = None) -> None:
        super().__init__(options)
        self._sequence: list[np.ndarray] = []
        self._next: list[int] = []
        self._repairing: list[int] = []
        """Per group, 1 while it refills the gaps a fault left."""

    def on_start(self, swarm: SwarmView) -> None:
        self._repairing = [0] * len(swarm.world.groups)
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

    def on_fault(self, swarm: SwarmView, group: int, robots: np.ndarray) -> None:
        """Repair: order the open cells anew and, unless a robot of the group is already on its
        way, restart the chain from a settled neighbour of a gap."""
        self._repairing[group] = 1
        self._order_open_targets(swarm)
        moving = (swarm.group == group) & (swarm.state == MOVING)
        if moving.any() or any(swarm.group[m.recipient] == group for m in swarm.pending):
            return
        self._hand_on(swarm, group, self._gap_neighbour(swarm, group))

    def _gap_neighbour(self, swarm: SwarmView, group: int) -> int:
        """A settled robot of the group next to one of its open cells, else the seeds."""
        robot_at = _robot_grid(swarm)
        for target in swarm.open_targets(group).tolist():
            for x, y in (swarm.targets[target] + STEPS[1:]).tolist():
                if 0 <= x < robot_at.shape[0] and 0 <= y < robot_at.shape[1]:
                    robot = int(robot_at[x, y])
                    if robot >= 0 and swarm.state[robot] == SETTLED:
                        return robot
        return SEEDS

    def _order_open_targets(self, swarm: SwarmView) -> None:
        """Each group's fill order, as target indices, without the cells already taken."""
        world = swarm.world
        first = np.cumsum([0] + [len(g.targets) for g in world.groups])
        taken = np.zeros(len(world.targets), dtype=bool)
        taken[swarm.target[swarm.target >= 0]] = True
        taken[[m.target for m in swarm.pending]] = True
        self._sequence = []
        for g in range(len(world.groups)):
            sequence = first[g] + fill_sequence(world, g, self.options.order, swarm.rng)
            self._sequence.append(sequence[~taken[sequence]])
        self._next = [0] * len(world.groups)

    def restore(self, saved: Snapshot, swarm: SwarmView) -> None:
        """Take the saved fill orders back, checked against the world they order."""
        super().restore(saved, swarm)
        groups, targets = len(swarm.world.groups), len(swarm.targets)
        if len(self._repairing) != groups or not all(r in (0, 1) for r in self._repairing):
            raise saved.error("_repairing", f"does not have one flag per group ({groups})")
        if len(self._sequence) != groups or len(self._next) != groups:
            raise saved.error("_sequence", f"does not have one order per group ({groups})")
        for group, (sequence, done) in enumerate(zip(self._sequence, self._next, strict=True)):
            if not isinstance(sequence, np.ndarray) or sequence.ndim != 1:
                raise saved.error("_sequence", "holds something other than lists of targets")
            in_range = sequence.dtype.kind == "i" and ((sequence >= 0) & (sequence < targets)).all()
            counted = type(done) is int and 0 <= done <= len(sequence)
            if not in_range or not counted:
                raise saved.error("_sequence", "names targets that do not exist")
            if (swarm.target_group[sequence] != group).any():
                raise saved.error("_sequence", "orders another group's targets")

    def on_settled(self, swarm: SwarmView, agents: np.ndarray) -> None:
        for agent in agents.tolist():
            self._hand_on(swarm, int(swarm.group[agent]), agent)

    def _hand_on(self, swarm: SwarmView, group: int, sender: int) -> None:
        """Send the group's next target to a random waiting robot, while targets remain.

        Once a shape was complete its spare robots wander; a changed shape recruits them.
        """
        if self._repairing[group]:
            self._repair(swarm, group, sender)
            return
        idle = swarm.waiting(group)
        if len(idle) == 0:
            idle = np.flatnonzero((swarm.group == group) & (swarm.state == WANDERING))
        if self._next[group] == len(self._sequence[group]) or len(idle) == 0:
            return
        recipient = int(swarm.rng.choice(idle))
        swarm.send(sender, recipient, int(self._sequence[group][self._next[group]]))
        self._next[group] += 1

    def _repair(self, swarm: SwarmView, group: int, sender: int) -> None:
        """One hand-on of a repair: the first reachable open cell in fill order goes to an idle
        robot that can reach it; if none can be reached, a settled neighbour of a gap moves
        into it (the neighbour nearest the free space), and the gap moves outward."""
        pending = [m.target for m in swarm.pending]
        open_cells = swarm.open_targets(group)
        open_cells = open_cells[~np.isin(open_cells, pending)]
        idle = swarm.idle(group)
        if len(open_cells) == 0:
            self._repairing[group] = 0
            return
        if len(idle) == 0:
            return
        world, robot_at = swarm.world, _robot_grid(swarm)
        passable = robot_at == -1
        passable[world.seeds[:, 0], world.seeds[:, 1]] = False
        others = world.targets[world.target_group != group]
        passable[others[:, 0], others[:, 1]] = False
        passable[swarm.cells[idle, 0], swarm.cells[idle, 1]] = True
        labels, _ = scipy.ndimage.label(passable)
        reached = np.unique(labels[swarm.cells[idle, 0], swarm.cells[idle, 1]])
        cells = swarm.targets[open_cells]
        reachable = np.isin(labels[cells[:, 0], cells[:, 1]], reached)
        if reachable.any():
            rank = np.full(len(swarm.targets), len(swarm.targets), dtype=np.int64)
            sequence = self._sequence[group]
            rank[sequence] = np.arange(len(sequence))
            candidates = open_cells[reachable]
            target = int(candidates[np.argmin(rank[candidates])])
            where = labels[swarm.targets[target][0], swarm.targets[target][1]]
            near = idle[labels[swarm.cells[idle, 0], swarm.cells[idle, 1]] == where]
            swarm.send(sender, int(swarm.rng.choice(near)), target)
            return
        mover, gap = self._nearest_shift(swarm, group, robot_at, np.isin(labels, reached))
        if mover >= 0:
            swarm.send(sender, mover, gap)

    def _nearest_shift(
        self, swarm: SwarmView, group: int, robot_at: np.ndarray, free: np.ndarray
    ) -> tuple[int, int]:
        """The settled robot next to an open cell that lies fewest settled cells from the free
        space `free`, and that cell; (-1, -1) if there is none."""
        settled = np.zeros(robot_at.shape, dtype=bool)
        mine = np.flatnonzero((swarm.group == group) & (swarm.state == SETTLED))
        settled[swarm.cells[mine, 0], swarm.cells[mine, 1]] = True
        distance = np.where(free, 0, np.iinfo(np.int64).max)
        front, level = free, 0
        while front.any():
            level += 1
            grown = scipy.ndimage.binary_dilation(front) & settled & (distance > level)
            distance[grown] = level
            front = grown
        best, choice = np.iinfo(np.int64).max, (-1, -1)
        for target in swarm.open_targets(group).tolist():
            for x, y in (swarm.targets[target] + STEPS[1:]).tolist():
                inside = 0 <= x < robot_at.shape[0] and 0 <= y < robot_at.shape[1]
                if inside and settled[x, y] and distance[x, y] < best:
                    best, choice = distance[x, y], (int(robot_at[x, y]), target)
        return choice


def _robot_grid(swarm: SwarmView) -> np.ndarray:
    """Which robot is at each cell of the arena (-1: none), robots that a fault took left out."""
    grid = np.full(swarm.world.size, -1, dtype=np.int64)
    here = np.flatnonzero(swarm.state != LOST)
    grid[swarm.cells[here, 0], swarm.cells[here, 1]] = here
    return grid

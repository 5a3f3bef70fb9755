"""The TSWAP rules on their own, and the ring case where a livelock was once found."""

from __future__ import annotations

import numpy as np

from swarmshape.core.lattice import FREE
from swarmshape.core.states import MOVING
from swarmshape.core.tswap import ring_members, rotate_rings, settled_swaps
from tests.conftest import grid_from, make_swarm


def test_ring_members_are_the_cycle_not_the_tail_that_leads_into_it():
    # 0 -> 1 -> 2 -> 0 is a ring; 3 waits for 0 and 4 for 3, but nobody waits for them
    waiting, waited_for = np.array([0, 1, 2, 3, 4]), np.array([1, 2, 0, 0, 3])
    assert ring_members(waiting, waited_for, robots=6).tolist() == [0, 1, 2]


def test_a_chain_without_a_ring_has_no_members():
    assert ring_members(np.array([0, 1]), np.array([1, 2]), robots=3).tolist() == []


def test_each_ring_member_hands_its_target_to_the_robot_it_waits_for():
    target = np.array([10, 11, 12, 13, 14])
    waiting, waited_for = np.array([0, 1, 2, 3]), np.array([1, 2, 0, 2])
    receivers, targets = rotate_rings(target, waiting, waited_for)
    target[receivers] = targets
    assert target.tolist() == [12, 10, 11, 13, 14], "3 is not on the ring; 4 never waited"


def test_one_waiting_robot_is_no_ring():
    receivers, _ = rotate_rings(np.arange(3), np.array([0]), np.array([0]))
    assert len(receivers) == 0


def test_a_settled_robot_swaps_with_only_one_mover_per_step():
    movers, settled = settled_swaps(np.array([5, 6, 7]), np.array([9, 9, 8]))
    assert sorted(zip(movers.tolist(), settled.tolist(), strict=True)) == [(5, 9), (7, 8)]


def place(swarm, robot, cell):
    swarm.lattice.grid[tuple(swarm.cell[robot])] = FREE
    swarm.cell[robot] = cell
    swarm.lattice.grid[tuple(cell)] = robot


def test_rotating_a_ring_does_not_reset_the_waiting_time():
    """Two movers facing each other, each heading past the other: they form a ring and trade
    targets. Their wait keeps counting, so movers that keep trading back and forth still reach
    the sidestep (this once livelocked: the rotation reset the count)."""
    swarm = make_swarm(grid_from("#.....#"), agents=2, seed=1, strategy="optimal")
    steering = swarm.driver
    left, right = swarm.world.targets[np.argsort(swarm.world.targets[:, 0])]
    middle = (left + right) // 2
    place(swarm, 0, middle)
    place(swarm, 1, middle + np.array([1, 0]))
    swarm.state[:] = MOVING
    goes_right, goes_left = (
        np.flatnonzero((swarm.world.targets == c).all(1))[0] for c in (right, left)
    )
    steering.target[:] = [goes_right, goes_left]  # each wants the cell the other is on
    steering.blocked[:] = 2
    steering.decide()
    assert steering.target.tolist() == [goes_left, goes_right], "the ring passed its targets round"
    assert steering.blocked.tolist() == [3, 3], "their waiting time kept counting"

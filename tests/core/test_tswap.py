"""The TSWAP rules on their own, and the ring case where a livelock was once found."""

from __future__ import annotations

import numpy as np

from swarmshape.core.lattice import FREE
from swarmshape.core.states import MOVING, SETTLED, WAITING
from swarmshape.core.tswap import one_per_blocker, ring_members, rotate_rings
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
    givers, receivers = rotate_rings(waiting, waited_for)
    target[receivers] = target[givers]
    assert target.tolist() == [12, 10, 11, 13, 14], "3 is not on the ring; 4 never waited"


def test_one_waiting_robot_is_no_ring():
    _, receivers = rotate_rings(np.array([0]), np.array([0]))
    assert len(receivers) == 0


def test_a_blocker_trades_with_only_one_mover_per_step():
    movers, settled = one_per_blocker(np.array([5, 6, 7]), np.array([9, 9, 8]))
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


def test_a_mover_that_just_traded_targets_does_not_also_swap_with_a_settled_robot():
    """A mover blocked by a settled robot, and a mover behind it that shortens both trips by
    trading targets with it, in one step: the traded target came to rest on the first mover's
    own cell, and swapping it on to the settled robot as well set three robots trading
    round a loop for good (a block with 5 % stalled early, under `random`)."""
    swarm = make_swarm(grid_from("#### ####"), seed=1, strategy="optimal")
    steering = swarm.driver
    targets = swarm.world.targets
    corner = targets.min(axis=0)

    def target_at(dx, dy):
        return int(np.flatnonzero((targets == corner + np.array([dx, dy])).all(axis=1))[0])

    settled, front, behind = 0, 1, 2
    for robot, (dx, dy) in zip((settled, front, behind), [(2, 0), (3, 0), (3, 1)], strict=True):
        place(swarm, robot, corner + np.array([dx, dy]))
    swarm.state[:] = WAITING  # the other five wait outside
    swarm.state[:3] = [SETTLED, MOVING, MOVING]
    swarm.filled[:] = False
    swarm.filled[target_at(2, 0)] = True
    swarm.direction[front] = 2  # heading -x, into the settled robot
    steering.target[:] = -1
    steering.target[:3] = [target_at(2, 0), target_at(0, 1), target_at(3, 0)]
    steering.blocked[:] = 0
    steering.decide()
    assert steering.target[behind] == target_at(0, 1), "the two movers traded targets"
    assert steering.target[front] == target_at(3, 0)
    assert swarm.state[settled] == SETTLED and steering.target[settled] == target_at(2, 0)


def test_ring_members_are_exactly_the_robots_a_walk_leads_back_to():
    rng = np.random.default_rng(0)
    for _ in range(200):
        robots = int(rng.integers(1, 30))
        waiting = rng.permutation(robots)[: rng.integers(0, robots + 1)]
        waited_for = rng.integers(0, robots, len(waiting))
        next_of = dict(zip(waiting.tolist(), waited_for.tolist(), strict=True))
        expected = []
        for robot in range(robots):
            at = next_of.get(robot)
            for _ in range(robots):
                if at is None or at == robot:
                    break
                at = next_of.get(at)
            if at == robot:
                expected.append(robot)
        assert ring_members(waiting, waited_for, robots).tolist() == expected

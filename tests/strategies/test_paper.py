from __future__ import annotations

import itertools

import numpy as np

from swarmshape.core.messages import SEEDS, MessageQueue
from swarmshape.core.shape import Shape
from swarmshape.core.states import State
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.runs import run
from swarmshape.strategies import create
from swarmshape.strategies.fill_order import fill_sequence
from tests.conftest import grid_from, make_swarm

SHAPE = grid_from("""
####
#..#
""")


def test_queue_delivers_in_order_once_and_keeps_a_log():
    queue = MessageQueue()
    queue.send(0, SEEDS, 4, 0)
    queue.send(0, 4, 2, 1)
    assert [m.recipient for m in queue.deliver()] == [4, 2]
    assert queue.deliver() == []
    assert len(queue.log) == 2


def test_the_baton_passes_from_the_seeds_along_each_settled_robot():
    swarm = make_swarm(SHAPE, seed=9)
    order = fill_sequence(swarm.world, 0, "outward", np.random.default_rng(0))
    run(swarm, max_steps=50_000)
    log = swarm.driver.queue.log
    assert log[0].sender == SEEDS and log[0].step == 0
    assert [m.target for m in log] == order.tolist()
    for before, after in itertools.pairwise(log):
        assert after.sender == before.recipient, "whoever settles sends the next message"
        assert after.step > before.step
    recipients = [m.recipient for m in log]
    assert len(set(recipients)) == len(recipients) == len(swarm.world.targets)


def test_only_one_robot_moves_at_a_time():
    swarm = make_swarm(SHAPE, seed=2)
    while not swarm.complete:
        swarm.step()
        assert (swarm.state == State.MOVING).sum() <= 1


def test_two_groups_movers_meeting_head_on_get_past_each_other():
    """Each group's one mover has its cell behind the other: both wait, plan round the other
    and step aside. Planning afresh in the same step, they stepped aside the same way, side by
    side, for good (hypothesis found it, two groups after faults)."""
    cell = np.ones((1, 1), dtype=bool)
    specs = [GroupSpec(name, Shape(cell), (200, 60, 60), 1) for name in "gh"]
    world = build_world(specs, (16, 14))
    west, east = world.targets[:, 0]
    assert west < east - 2, "g's cell lies west of h's, with room between"
    for y, seed in itertools.product(range(2, 13), range(3)):
        start = np.array([[east - 1, y], [east - 2, y]])  # g's robot east of h's
        swarm = Swarm(world, create("paper"), seed, start=start)
        run(swarm, max_steps=300)
        assert swarm.complete, f"robots starting in row {y}, seed {seed}"

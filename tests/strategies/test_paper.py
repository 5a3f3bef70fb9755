from __future__ import annotations

import itertools

import numpy as np

from swarmshape.core.messages import SEEDS, MessageQueue
from swarmshape.core.states import State
from swarmshape.runs import run
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

"""`local-swap` (Wang and Rubenstein 2020) with messages lost: the goal-less robots reach the
cells that lost messages left open."""

from __future__ import annotations

from swarmshape.runs import build, configure, run
from tests.conftest import SHAPES


def test_goal_less_robots_find_their_way_round_to_open_cells_with_messages_lost():
    """The star with 10 % of messages lost, seed 3, stopped at 98.6 % for good: the robots
    without a goal, outside on the far side, sensed a filled cell open each time they moved
    (from between two cells), turned to it and back to the news of the real open cells every
    few steps, and so never counted as stuck and never went round the shape."""
    config = configure(SHAPES / "star.png", strategy="local-swap", seed=3, msg_loss=0.1)
    swarm = run(build(config), max_steps=3000)
    assert swarm.complete
    assert swarm.overlap_total == 0

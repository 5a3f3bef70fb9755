"""`mean-shift` (Sun et al. 2023 on the lattice) forms small shapes, holes and one-cell arms
included, within a bounded number of steps, the same run for the same seed, and reads its
options."""

from __future__ import annotations

import numpy as np
import pytest

from swarmshape.config import configure
from swarmshape.core.metrics import run_metrics
from swarmshape.runs import build, load_world, run, start_swarm
from swarmshape.strategies.mean_shift import IN_PLACE
from tests.conftest import SHAPES


def formed(shape: str, max_steps: int = 3000, **settings):
    config = configure(SHAPES / shape, strategy="mean-shift", **settings)
    return run(build(config), max_steps=max_steps)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(
    ("shape", "cells"), [("star.png", 12), ("ring.png", 10), ("horseshoe.png", None)]
)
def test_small_shapes_with_arms_and_holes_form_whole_without_overlaps(shape, cells, seed):
    swarm = formed(shape, cells=cells, seed=seed)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0
    assert (swarm.driver.memory.state[swarm.present] == IN_PLACE).all()


def test_spare_robots_wait_outside_a_formed_shape():
    swarm = formed("star.png", cells=12, agents=60, seed=4)
    assert swarm.complete
    assert swarm.overlap_total == 0


def test_the_same_seed_gives_the_same_run():
    a, b = (formed("star.png", cells=12, seed=7) for _ in "ab")
    assert a.step_count == b.step_count
    assert np.array_equal(a.cell, b.cell)
    assert np.array_equal(a.driver.memory.news_hops, b.driver.memory.news_hops)


def test_without_the_entering_command_robots_outside_never_come_in():
    """The options reach the program: with the entering gain at 0 only robots that already
    sense a free cell of the shape move toward it, so most robots, scattered far off, never
    come in; with it the same start forms the shape."""
    still = formed("star.png", max_steps=400, cells=12, seed=5, options={"entering": 0.0})
    assert run_metrics(still)["coverage"] < 0.5
    assert formed("star.png", max_steps=3000, cells=12, seed=5).complete


def test_a_robot_in_the_rings_middle_is_let_in_by_a_hole_carried_to_it():
    """Every robot but one on the ring, that one in its middle, and the one empty cell on the
    outer rim: robots in place carry holes outward, away from the middle, so this hole must be
    carried in to it (`holes.pulled`; the 672-robot ring stopped a cell short for want of it)."""
    config = configure(SHAPES / "ring.png", strategy="mean-shift", cells=16, seed=0)
    world = load_world(config)
    targets = world.targets
    middle = np.floor(targets.mean(axis=0)).astype(np.int64)
    assert not (targets == middle).all(axis=1).any(), "the middle is off the ring"
    outermost = np.argmax(np.abs(targets - middle).sum(axis=1))
    start = np.concatenate([np.delete(targets, outermost, axis=0), [middle]])
    swarm = run(start_swarm(config, world, start), max_steps=2000)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0

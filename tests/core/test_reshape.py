"""Live re-forming: a running swarm takes a new shape without a restart."""

from __future__ import annotations

import numpy as np
import pytest

from swarmshape.core.shape import Pose, Shape
from swarmshape.core.states import SETTLED
from swarmshape.core.world import WorldError
from swarmshape.runs import run
from swarmshape.strategies import available
from tests.conftest import make_swarm

BEFORE = np.ones((6, 6), dtype=bool)
AFTER = np.zeros((8, 6), dtype=bool)
AFTER[:6, :5] = True  # the right column goes away ...
AFTER[6:, :5] = True  # ... and two rows grow underneath


@pytest.mark.parametrize("strategy", sorted(available()))
def test_reshaping_keeps_agents_on_kept_cells_and_completes_the_new_shape(strategy):
    swarm = make_swarm(BEFORE, agents=46, seed=3, strategy=strategy)
    run(swarm, max_steps=100_000)
    assert swarm.complete
    old_targets = {tuple(c) for c in swarm.world.targets.tolist()}
    swarm.reshape(0, Shape(AFTER))
    new_targets = {tuple(c) for c in swarm.world.targets.tolist()}
    kept = [
        a
        for a in np.flatnonzero(swarm.state == SETTLED).tolist()
        if tuple(swarm.cell[a]) in old_targets & new_targets
    ]
    assert len(kept) == len(old_targets & new_targets) == 30
    kept_cells = swarm.cell[kept].copy()
    removed = [
        a for a in range(len(swarm.cell)) if tuple(swarm.cell[a]) in old_targets - new_targets
    ]
    assert len(removed) == 6 and (swarm.state[removed] != SETTLED).all()
    assert not swarm.complete
    while not swarm.complete and swarm.step_count < 200_000:
        swarm.step()
        assert np.array_equal(swarm.cell[kept], kept_cells), "kept agents never move"
        assert (swarm.offset[kept] == 0).all()
    assert swarm.complete
    assert swarm.overlap_total == 0
    assert {tuple(c) for c in swarm.cell[swarm.state == SETTLED].tolist()} == new_targets


def test_a_shape_change_before_completion_also_finishes():
    swarm = make_swarm(BEFORE, agents=40, seed=5, strategy="optimal")
    for _ in range(15):
        swarm.step()
    swarm.reshape(0, Shape(AFTER))
    run(swarm, max_steps=20_000)
    assert swarm.complete and swarm.overlap_total == 0


def test_seeds_cannot_move_onto_robots_or_out_of_the_arena():
    swarm = make_swarm(BEFORE, agents=40, seed=5, strategy="optimal")
    width, height = swarm.world.size
    fits = (swarm.cell[:, 0] + 7 <= width) & (swarm.cell[:, 1] + 7 <= height)
    x, y = swarm.cell[np.flatnonzero(fits)[0]] + 1  # seed (-1, -1) of this pose lands on it
    with pytest.raises(WorldError, match="taken by robots"):
        swarm.reshape(0, Shape(BEFORE), Pose(int(x), int(y)))
    with pytest.raises(WorldError, match="outside"):
        swarm.reshape(0, Shape(BEFORE), Pose(10_000, 0))


def test_repeated_changes_complete_even_over_wandering_agents_and_pending_messages():
    from swarmshape.io.bitmap import load_grid
    from tests.conftest import SHAPES

    shapes = [Shape(load_grid(SHAPES / name)) for name in ("horseshoe.png", "square.png")]
    swarm = make_swarm(shapes[0].grid, agents=120, seed=1, strategy="paper")
    for change in range(1, 5):
        run(swarm, max_steps=swarm.step_count + 15_000)
        assert swarm.complete, f"change {change}: coverage {swarm.filled.mean():.2f}"
        swarm.reshape(0, shapes[change % 2])
    assert swarm.overlap_total == 0


def test_a_shape_with_more_cells_than_robots_is_refused_in_one_line_and_nothing_changes():
    """Issue 29, cases 6 and 17: a live change to 15 cells for 4 robots went ahead, never
    formed, and made the metrics raise at the end."""
    from swarmshape.core.metrics import run_metrics

    swarm = make_swarm(np.ones((1, 4), dtype=bool), seed=1, strategy="optimal")
    run(swarm, max_steps=200)
    before = swarm.world
    with pytest.raises(WorldError) as error:
        swarm.reshape(0, Shape(np.ones((3, 5), dtype=bool)))
    assert str(error.value) == (
        "group 'test': the new shape has 15 cells for the 4 robots that can move: short by 11; "
        "draw fewer cells, or fit it with shape.fitted(4)"
    )
    assert swarm.world is before and swarm.complete
    assert run_metrics(swarm)["coverage"] == 1.0


def test_after_a_fault_a_change_is_measured_against_the_robots_left():
    """Issue 29, case 17: after a fault the editor offered the robots the run began with, and
    a shape for them sat at 83 % for good."""
    swarm = make_swarm(BEFORE, agents=36, seed=2, strategy="greedy")
    run(swarm, max_steps=2_000)
    swarm.fail(np.arange(6))
    run(swarm, max_steps=swarm.step_count + 5_000)
    assert swarm.complete and swarm.movable(0) == 30
    with pytest.raises(WorldError, match="36 cells for the 30 robots that can move: short by 6"):
        swarm.reshape(0, Shape(BEFORE))
    swarm.reshape(0, Shape(BEFORE).fitted(30))
    run(swarm, max_steps=swarm.step_count + 5_000)
    assert swarm.complete

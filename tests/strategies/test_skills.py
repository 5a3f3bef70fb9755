"""The compiled skills that local programs share give what the plain numpy and scipy ways
give: breadth-first distances through robots' view squares, and a shape's values round each
robot's frame cell."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.core.perception import Blueprint
from swarmshape.strategies.mean_shift import explore
from swarmshape.strategies.mean_shift.explore import grey
from swarmshape.strategies.skills import shape
from swarmshape.strategies.skills.localise import roam
from swarmshape.strategies.skills.relay import best_per_robot
from swarmshape.strategies.skills.view import distances
from tests.conftest import dilated, grid_from


@settings(deadline=None)  # the first example compiles the kernel
@given(st.integers(0, 2**32 - 1), st.integers(1, 9), st.floats(0.0, 0.7))
def test_distances_count_the_moves_that_scipys_dilation_counts(seed, side, crowd):
    rng = np.random.default_rng(seed)
    blocked = rng.random((3, side, side)) < crowd
    sources = rng.random((3, side, side)) < 0.1
    steps = distances(blocked, sources)
    for square in range(3):
        assert np.array_equal(steps[square], dilated(blocked[square], sources[square]))


def test_distances_leave_a_blocked_source_and_reach_nothing_through_walls():
    blocked = grid_from("### #.# ###")[None]
    sources = np.zeros_like(blocked)
    sources[0, 0, 0] = True
    steps = distances(blocked, sources)
    assert steps[0, 0, 0] == 0 and (steps[0][blocked[0]][1:] == -1).all()
    assert steps[0, 1, 1] == -1, "the middle cell is walled in"


def test_the_square_round_each_frame_cell_holds_what_a_lookup_of_each_cell_gives():
    blueprint = Blueprint.of(
        [np.argwhere(grid_from("##. .## ..#")), np.argwhere(grid_from("#### #..#"))]
    )
    rng = np.random.default_rng(3)
    groups = rng.integers(0, 2, 40)
    frame = rng.integers(-12, 12, (40, 2))  # well off the boxes too, where lookups clip
    reach = 3
    around = shape.Around(blueprint, groups, frame, reach)
    span = np.arange(-reach, reach + 1)
    offsets = np.stack(np.meshgrid(span, span, indexing="ij"), axis=-1).reshape(-1, 2)
    every = np.broadcast_to(offsets, (40, len(offsets), 2))
    cells = (frame[:, None] + offsets).reshape(-1, 2)
    looked_up = np.repeat(groups, len(offsets))
    depth = shape.depth(blueprint, looked_up, cells).reshape(40, -1)
    inside = blueprint.contains(looked_up, cells).reshape(40, -1)
    assert np.array_equal(around.depth(offsets[None]), depth)
    assert np.array_equal(around.depth(every), depth)
    assert np.array_equal(around.contains(every), inside)
    assert np.array_equal(around.contains(offsets[7] + 0 * frame), inside[:, 7])
    assert np.array_equal(around.enclosed(every), (depth > 0) & ~inside)
    some = np.array([3, 17, 39])
    assert np.array_equal(around.depth(every[some], some), depth[some])


def test_squares_taken_over_from_the_last_step_are_those_worked_out_afresh():
    """`Around` takes over the last step's squares and works out again only the rows of
    robots whose group or frame cell changed: the same squares as worked out for all."""
    ring = np.argwhere(grid_from("##### #...# #.#.# #...# #####"))  # a sealed dot in it
    blueprint = Blueprint.of([ring, np.argwhere(grid_from("#### #..#"))])
    rng = np.random.default_rng(5)
    groups, frame = rng.integers(0, 2, 40), rng.integers(-8, 8, (40, 2))
    last = shape.Around(blueprint, groups, frame, 3)
    for _ in range(3):
        groups = np.where(rng.random(40) < 0.2, 1 - groups, groups)
        frame = frame + rng.integers(-1, 2, (40, 2)) * (rng.random((40, 1)) < 0.3)
        last = shape.Around(blueprint, groups, frame, 3, last)
        fresh = shape.Around(blueprint, groups, frame, 3)
        assert np.array_equal(last.inside, fresh.inside)
        assert np.array_equal(last.depths, fresh.depths)
        assert np.array_equal(last.sealed(explore.square(3)), fresh.sealed(explore.square(3)))
    other = Blueprint.of([ring, np.argwhere(grid_from("## ##"))])  # a reshape: none taken over
    fresh = shape.Around(other, groups, frame, 3)
    assert np.array_equal(shape.Around(other, groups, frame, 3, last).depths, fresh.depths)


def test_a_cell_beyond_the_square_worked_out_is_refused_not_wrapped_round():
    blueprint = Blueprint.of([np.argwhere(grid_from("## ##"))])
    around = shape.Around(blueprint, np.zeros(2, dtype=np.int64), np.zeros((2, 2), int), 2)
    with pytest.raises(ValueError, match="beyond"):
        around.depth(np.array([[[-3, 0]]]))


def test_lookups_over_no_robot_give_nothing_and_a_bad_entry_owner_is_refused():
    """Faults can leave a group no robot to look up for; the compiled passes check no index,
    so an entry said to belong to a robot there is not is refused before them (found by a
    review at stop 64: numpy's reshape raised on no robot, and the compiled pass crashed the
    process on an owner out of range)."""
    blueprint = Blueprint.of([np.argwhere(grid_from("## ##"))])
    none = np.zeros(0, dtype=np.int64)
    assert grey(blueprint, none, np.zeros((0, 5, 2), dtype=np.int64)).shape == (0, 5)
    assert grey(blueprint, none, np.zeros((0, 2), dtype=np.int64)).shape == (0,)
    keys, mask = np.array([3, 1, 2]), np.ones(3, dtype=bool)
    assert best_per_robot(2, np.array([0, 0, 1]), keys, mask).tolist() == [1, 2]
    with pytest.raises(IndexError, match="robots 0 to 2"):
        best_per_robot(2, np.array([0, 1, 2]), keys, mask)


class AtRest(SimpleNamespace):
    """Robots at rest whose last step moved them nowhere, as a perception shows them."""

    def __init__(self, robots: int) -> None:
        super().__init__(
            ready=np.ones(robots, dtype=bool),
            moved=np.zeros((robots, 2)),
            cruising=np.zeros(robots, dtype=bool),
            heading=np.zeros(robots, dtype=np.int64),
        )

    def __len__(self) -> int:
        return len(self.ready)


@pytest.mark.parametrize("way", [0, 1, 2, 3, 4])
def test_a_roaming_robot_sets_out_any_way_but_the_one_that_failed(way):
    """With no way yet, or after a stop to turn, a roaming robot (`mean-shift`,
    `self-assembly`) never set out along move 1: the draw skipped the way that failed even
    when there was none."""
    robots = 4000
    moves = roam(
        AtRest(robots),
        np.full(robots, way),
        np.ones(robots, dtype=bool),
        lambda rows, cells: np.zeros(len(rows), dtype=bool),
        20,
        np.random.default_rng(0),
    )
    counts = np.bincount(moves, minlength=5)
    assert counts[0] == 0 and (way == 0 or counts[way] == 0)
    others = [move for move in range(1, 5) if move != way]
    assert (counts[others] > robots / (len(others) + 1)).all(), counts

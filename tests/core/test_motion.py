from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.core.audit import overlapping_pairs
from swarmshape.core.motion import STEPS, Limits, advance, move


def brute_force_pairs(pos):
    n = len(pos)
    return {
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if np.abs(pos[i] - pos[j]).max() < 1 - 1e-9
    }


POINTS = st.lists(
    st.tuples(st.floats(-6, 6, allow_nan=False), st.floats(-6, 6, allow_nan=False)),
    max_size=120,
)


@settings(max_examples=60, deadline=None)
@given(POINTS)
def test_spatial_hash_finds_exactly_the_overlapping_pairs(points):
    pos = np.array(points, dtype=np.float64).reshape(-1, 2)
    i, j = overlapping_pairs(pos)
    found = {(min(a, b), max(a, b)) for a, b in zip(i.tolist(), j.tolist(), strict=True)}
    assert len(found) == len(i), "each pair once"
    assert found == brute_force_pairs(pos)


def test_a_square_at_no_finite_place_overlaps_nothing_and_the_others_are_still_checked():
    pos = np.array([[np.nan, 0.5], [0.5, 0.5], [np.inf, np.inf], [0.9, 0.7]])
    assert [pair.tolist() for pair in overlapping_pairs(pos)] == [[1], [3]]


def test_touching_squares_do_not_overlap():
    pos = np.array([[0.5, 0.5], [1.5, 0.5], [0.5, 1.5], [1.5, 1.5]])
    assert len(overlapping_pairs(pos)[0]) == 0


def test_speed_and_acceleration_stay_within_limits_and_agents_stop_on_a_centre():
    limits = Limits(max_speed=0.5, max_accel=0.125)
    for run in (1, 2, 3, 7):
        offset, speed, ahead = np.zeros(1), np.zeros(1), np.array([run])
        speeds = []
        for _ in range(40):
            advance(offset, speed, ahead, limits)
            speeds.append(speed[0])
        assert max(speeds) <= 0.5 + 1e-12
        assert np.all(np.abs(np.diff([0.0, *speeds])) <= 0.125 + 1e-12)
        assert offset[0] == float(run) and speeds[-1] == 0.0


def test_a_train_of_any_length_starts_as_one_and_keeps_its_gaps():
    """200 robots in a row, each following the one ahead east, all at rest with three cells
    to go: the first step moves every one of them, none nearer the next than touching (64
    passes used to leave all but the first 64 links standing)."""
    n = 200
    east = int(np.flatnonzero((STEPS == (1, 0)).all(axis=1))[0])
    cell = np.stack([np.arange(n)[::-1] + 1, np.full(n, 1)], axis=1).astype(np.int64)
    direction, ahead = np.full(n, east), np.full(n, 3)
    offset, speed, distance, pace = np.zeros(n), np.zeros(n), np.zeros(n), np.ones(n)
    leader = np.arange(n) - 1  # robot k follows robot k - 1, the head follows nobody
    stride = 4
    holder = np.full((n + 6) * stride, -1, dtype=np.int64)
    queued = holder.copy()
    for _ in range(3):
        move(cell, direction, ahead, offset, speed, distance, pace, leader, holder, queued,
             stride, 0.5, 0.125)  # fmt: skip
        assert (distance > 0).all()
        x = cell[:, 0] + offset
        assert (np.diff(x[::-1]) >= 1.0 - 1e-9).all(), "a whole cell behind the one it follows"

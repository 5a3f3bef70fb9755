from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from swarmshape.core.shape import Shape
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.strategies.fill_order import ORDERS, fill_sequence
from tests.conftest import grid_from

RING = grid_from("""
#####
#...#
#.#.#
#...#
#####
""")


def world_of(grid):
    return build_world([GroupSpec("g", Shape(grid), (1, 2, 3))])


def reachable_each_turn(world, sequence):
    """Whether every cell, at its turn, touches the open arena through unfilled cells."""
    blocked = world.mask(world.seeds)
    for i in sequence:
        x, y = world.targets[i]
        labels, _ = ndimage.label(~blocked)
        border = set(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
        if labels[x, y] not in border:
            return False
        blocked[x, y] = True
    return True


def test_left_to_right_fills_columns_in_order():
    world = world_of(np.ones((2, 5), dtype=bool))
    sequence = fill_sequence(world, 0, "left-to-right", np.random.default_rng(0))
    xs = world.groups[0].frame_cells[sequence, 0]
    assert xs.tolist() == sorted(xs.tolist())


def test_outward_grows_connected_from_the_seeds():
    world = world_of(np.ones((6, 6), dtype=bool))
    sequence = fill_sequence(world, 0, "outward", np.random.default_rng(0))
    placed = world.mask(world.seeds)
    for i in sequence:
        x, y = world.targets[i]
        assert placed[x - 1 : x + 2, y].any() or placed[x, y - 1 : y + 2].any()
        placed[x, y] = True


def test_random_order_depends_on_the_seed():
    world = world_of(np.ones((4, 4), dtype=bool))
    a = fill_sequence(world, 0, "random", np.random.default_rng(1))
    b = fill_sequence(world, 0, "random", np.random.default_rng(2))
    assert sorted(a.tolist()) == sorted(b.tolist()) == list(range(16))
    assert a.tolist() != b.tolist()


@pytest.mark.parametrize("order", ORDERS)
def test_no_order_walls_in_a_cell_of_a_ring(order):
    world = world_of(RING)
    sequence = fill_sequence(world, 0, order, np.random.default_rng(0))
    assert sorted(sequence.tolist()) == list(range(len(world.targets)))
    assert reachable_each_turn(world, sequence)


@settings(max_examples=40, deadline=None)
@given(
    bits=st.lists(st.booleans(), min_size=36, max_size=36),
    order=st.sampled_from(ORDERS),
    seed=st.integers(0, 2**32 - 1),
)
def test_every_order_keeps_every_cell_reachable_on_random_bitmaps(bits, order, seed):
    grid = np.array(bits).reshape(6, 6)
    if not grid.any():
        grid[0, 0] = True
    world = world_of(grid)
    sequence = fill_sequence(world, 0, order, np.random.default_rng(seed))
    assert sorted(sequence.tolist()) == list(range(len(world.targets)))
    assert reachable_each_turn(world, sequence)

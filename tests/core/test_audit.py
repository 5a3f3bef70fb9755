"""The overlap audit works from positions alone, so it catches what the reservations miss."""

from __future__ import annotations

import numpy as np

from swarmshape.core.audit import overlaps
from swarmshape.core.lattice import FREE
from tests.conftest import grid_from, make_swarm

SHAPE = grid_from("""
###
#.#
""")


def audit(swarm):
    return overlaps(swarm.cell, swarm.direction, swarm.offset, swarm.world.seeds, swarm.world.size)


def test_an_overlap_is_found_even_when_the_reservations_miss_it():
    swarm = make_swarm(SHAPE, seed=1, strategy="optimal")
    a, b = 0, 1
    # corrupt the state on purpose: b is put halfway into a's cell behind the lattice's back
    swarm.lattice.grid[tuple(swarm.cell[b])] = FREE
    swarm.cell[b] = swarm.cell[a] + np.array([-1, 0])
    swarm.direction[b], swarm.offset[b], swarm.ahead[b] = 1, 0.5, 1
    i, j = audit(swarm)
    assert sorted([int(i[0]), int(j[0])]) == [a, b] and len(i) == 1


def test_a_robot_on_a_seed_is_an_overlap_with_that_seed():
    swarm = make_swarm(SHAPE, seed=1, strategy="optimal")
    swarm.cell[3] = swarm.world.seeds[2]
    i, j = audit(swarm)
    assert (int(i[0]), int(j[0])) == (3, len(swarm.cell) + 2)


def test_a_clean_run_has_no_overlaps_at_any_step():
    swarm = make_swarm(SHAPE, seed=2, strategy="optimal", agents=9)
    while not swarm.complete:
        swarm.step()
        assert len(audit(swarm)[0]) == 0
    assert swarm.overlap_total == 0

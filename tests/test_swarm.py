from __future__ import annotations

import numpy as np

from swarmshape.motion import FREE
from tests.conftest import grid_from, make_swarm

SHAPE = grid_from("""
###
#.#
""")


def test_an_overlap_is_counted_even_when_the_reservations_miss_it():
    swarm = make_swarm(SHAPE, seed=1, strategy="optimal")
    a, b = 0, 1
    # corrupt the state on purpose: b is put halfway into a's cell behind the reservations' back
    swarm.occupancy[tuple(swarm.cell[b])] = FREE
    swarm.cell[b] = swarm.cell[a] + np.array([-1, 0])
    swarm.direction[b], swarm.offset[b], swarm.ahead[b] = 1, 0.5, 1
    swarm._observe()
    assert swarm.overlap_total == 1
    assert swarm.overlaps[0] == 1


def test_a_clean_run_has_no_suspects_at_any_step():
    swarm = make_swarm(SHAPE, seed=2, strategy="optimal", agents=9)
    while not swarm.complete:
        swarm.step()
        assert len(swarm._overlap_suspects()) == 0

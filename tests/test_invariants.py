"""Invariants that hold at every step, for random bitmaps, agent counts, arenas, seeds and
every strategy (hypothesis; more examples with ``pytest --slow``)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.motion import overlapping_pairs
from swarmshape.shape import Shape
from swarmshape.strategies import available, create
from swarmshape.swarm import SETTLED, Swarm
from swarmshape.world import GroupSpec, build_world

STRATEGIES = sorted(available())


def check_every_step(swarm: Swarm, steps: int) -> None:
    width, height = swarm.world.size
    seeds = swarm.world.seeds + 0.5
    complete_at = None
    for _ in range(steps):
        settled_before = swarm.state == SETTLED
        cells_before = swarm.cell.copy()
        coverage_before = swarm.filled.mean()
        swarm.step()
        pos = swarm.positions()
        assert np.isfinite(pos).all() and np.isfinite(swarm.speed).all()
        assert (pos >= 0.5).all() and (pos[:, 0] <= width - 0.5).all()
        assert (pos[:, 1] <= height - 0.5).all(), "nobody leaves the arena"
        assert len(swarm.cell) == swarm.world.agents, "agents are conserved"
        i, _ = overlapping_pairs(np.concatenate([pos, seeds]))
        assert len(i) == 0, "no two squares overlap, seeds included"
        still = settled_before & (swarm.state == SETTLED)
        assert (swarm.cell[still] == cells_before[still]).all(), "settled agents stay put"
        if complete_at is not None:
            assert swarm.filled.mean() >= coverage_before, "coverage never drops once complete"
        if swarm.complete and complete_at is None:
            complete_at = swarm.step_count
    assert swarm.overlap_total == 0


@settings(deadline=None)
@given(
    bits=st.lists(st.booleans(), min_size=20, max_size=20),
    strategy=st.sampled_from(STRATEGIES),
    spare=st.integers(-3, 6),
    room=st.integers(0, 12),
    seed=st.integers(0, 2**32 - 1),
)
def test_invariants_hold_at_every_step(bits, strategy, spare, room, seed):
    grid = np.array(bits).reshape(4, 5)
    if not grid.any():
        grid[1, 1] = True
    agents = max(1, int(grid.sum()) + spare)
    spec = GroupSpec("g", Shape(grid), (1, 2, 3), agents)
    auto = build_world([spec])
    arena = (auto.size[0] + room, auto.size[1] + room // 2)
    world = build_world([spec], arena)
    runs = []
    for _ in range(2):
        swarm = Swarm(world, create(strategy), seed)
        check_every_step(swarm, 400 if strategy != "paper" else 1500)
        runs.append(swarm)
    assert runs[0].step_count == runs[1].step_count
    assert np.array_equal(runs[0].cell, runs[1].cell), "deterministic per seed"
    assert np.array_equal(runs[0].state, runs[1].state)

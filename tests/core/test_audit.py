"""The overlap audit works from positions alone, so it catches what the reservations miss."""

from __future__ import annotations

import numpy as np

from swarmshape.core.audit import Audit, new_scratch, overlaps
from swarmshape.core.lattice import FREE
from swarmshape.core.motion import STEPS, TOUCH, positions
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


def test_every_overlapping_pair_is_found_among_squares_thrown_at_random():
    """Squares thrown about at random (between cells too, onto seeds, some absent): the audit
    names exactly the pairs whose centres are closer than a side on both axes, the test any
    pair of unit squares must pass, checked here against every pair."""
    rng = np.random.default_rng(0)
    size, seeds = (7, 6), np.array([[0, 0], [1, 0], [0, 1]])
    scratch = new_scratch(size)
    found = 0
    for _ in range(200):
        n = int(rng.integers(2, 14))
        cell = rng.integers(0, np.array(size) - 1, (n, 2))
        direction = rng.integers(0, 5, n)
        offset = np.where(direction > 0, rng.choice([0.0, 0.25, 0.5, 1 - 1e-12], n), 0.0)
        present = rng.random(n) < 0.9
        i, j = overlaps(cell, direction, offset, seeds, size, present, scratch)
        centres = np.concatenate([positions(cell, direction, offset), seeds + 0.5])
        there = np.concatenate([present, np.ones(len(seeds), dtype=bool)])
        close = np.abs(centres[:, None] - centres[None]).max(axis=2) < TOUCH
        close &= there[:, None] & there[None] & ~np.eye(len(there), dtype=bool)
        expected = {(int(a), int(b)) for a, b in zip(*np.nonzero(np.triu(close)), strict=True)}
        assert {
            (min(a, b), max(a, b)) for a, b in zip(i.tolist(), j.tolist(), strict=True)
        } == expected
        assert (scratch == -1).all()
        found += len(expected)
    assert found > 50


def _clean_squares(rng, size, seeds, n):
    """`n` squares that do not overlap: each on its own cell off the seeds, some under way
    into a free cell beside it that no other square covers."""
    free = np.ones(size, dtype=bool)
    free[seeds[:, 0], seeds[:, 1]] = False
    cells = np.argwhere(free)[rng.permutation(int(free.sum()))[:n]]
    free[cells[:, 0], cells[:, 1]] = False
    direction, offset = np.zeros(n, dtype=np.int64), np.zeros(n)
    for r in rng.permutation(n)[: n // 2]:
        d = int(rng.integers(1, 5))
        x, y = cells[r] + STEPS[d]
        if 0 <= x < size[0] and 0 <= y < size[1] and free[x, y]:
            free[x, y] = False
            direction[r], offset[r] = d, rng.choice([0.25, 0.5, 1 - 1e-12])
    return cells, direction, offset


def test_the_audit_kept_from_step_to_step_names_what_the_whole_audit_names():
    """A run of states, each a few squares changed from the last (come to rest, set out, gone,
    back), now and then pushed into another's cell or onto a seed: at every step `Audit` names
    the same pairs as `overlaps`, and most clean steps are audited by the squares that moved."""
    rng = np.random.default_rng(1)
    size, seeds = (9, 8), np.array([[0, 0], [1, 0], [0, 1]])
    n = 20
    scratch, auditor = new_scratch(size), Audit(size)
    cell, direction, offset = _clean_squares(rng, size, seeds, n)
    present = np.ones(n, dtype=bool)
    kept, overlapping = 0, 0
    for _ in range(400):
        change = rng.permutation(n)[: int(rng.integers(1, 4))]
        fresh = _clean_squares(rng, size, seeds, n)  # clean among themselves, not with the rest
        now = cell.copy(), direction.copy(), offset.copy()
        for array, new in zip(now, fresh, strict=True):
            array[change] = new[change]
        centres = positions(*now)
        others = np.abs(centres[:, None] - centres[None]).max(axis=2) < TOUCH
        on_seeds = np.abs(centres[:, None] - (seeds + 0.5)[None]).max(axis=2) < TOUCH
        if (np.triu(others, 1).any() or on_seeds.any()) and rng.random() < 0.8:
            now = fresh  # clean again, every square changed at once
        cell, direction, offset = now
        present[change] = rng.random(len(change)) < 0.9
        was_kept = not auditor.stale
        i, j = auditor.pairs(cell, direction, offset, seeds, present, scratch)
        expected = overlaps(cell, direction, offset, seeds, size, present, scratch)
        named = sorted(zip(i.tolist(), j.tolist(), strict=True))
        assert named == sorted(zip(expected[0].tolist(), expected[1].tolist(), strict=True))
        assert (scratch == -1).all()
        kept += was_kept and len(i) == 0
        overlapping += len(i) > 0
    assert kept > 100 and overlapping > 20


def test_a_swarm_counts_an_overlap_made_behind_the_reservations_back():
    """The swarm's own audit, kept from step to step, counts a square pushed into a cell
    another rests on while it was not looking."""
    swarm = make_swarm(SHAPE, seed=2, strategy="optimal", agents=9)
    swarm.step()
    swarm.step()
    assert swarm.overlap_total == 0
    a, b = np.flatnonzero(swarm.offset == 0)[:2]
    swarm.cell[b] = swarm.cell[a]  # b is moved onto a's cell behind the lattice's back
    swarm.step()
    assert swarm.overlap_total >= 1

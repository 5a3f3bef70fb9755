"""`perception.neighbours` finds, for every robot, what lies within its reach, nearest first:
the same rows as the plain loop over offsets it replaced (kept here as the reference)."""

from __future__ import annotations

import numpy as np
import pytest

from swarmshape.core.perception import Senses, neighbours, turn


def reference(cell, seeds, size, reach):
    n = len(cell)
    r = int(np.abs(reach).max())
    who = np.full((size[0] + 2 * r, size[1] + 2 * r), -1, dtype=np.int64)
    who[cell[:, 0] + r, cell[:, 1] + r] = np.arange(n)
    who[seeds[:, 0] + r, seeds[:, 1] + r] = n + np.arange(len(seeds))
    owners, others = [], []
    for dx, dy in reach:
        found = who[cell[:, 0] + r + dx, cell[:, 1] + r + dy]
        hit = np.flatnonzero(found >= 0)
        owners.append(hit)
        others.append(found[hit])
    owner, other = np.concatenate(owners), np.concatenate(others)
    order = np.argsort(owner, kind="stable")
    owner, other = owner[order], other[order]
    return np.searchsorted(owner, np.arange(n + 1)), owner, other


@pytest.mark.parametrize("radius", [1.0, 2.5, 3.0, 5.0])
@pytest.mark.parametrize("seed", range(4))
def test_neighbours_match_the_plain_loop(radius, seed):
    rng = np.random.default_rng(seed)
    size = (int(rng.integers(3, 30)), int(rng.integers(3, 30)))
    cells = np.argwhere(np.ones(size, dtype=bool))
    picked = cells[rng.permutation(len(cells))[: int(rng.integers(1, len(cells)))]]
    seeds, cell = picked[:3], picked[3:]
    reach = Senses(radius).reach()
    for mine, theirs in zip(
        neighbours(cell, seeds, size, reach), reference(cell, seeds, size, reach), strict=True
    ):
        np.testing.assert_array_equal(mine, theirs)


def test_no_turn_copies_and_turns_rotate():
    vectors = np.array([[1.5, -2.0], [0.0, 1.0]])
    same = turn(vectors, np.zeros(2, dtype=np.int64))
    assert same is not vectors and np.array_equal(same, vectors)
    np.testing.assert_array_equal(turn(vectors, np.array([1, 2])), [[2.0, 1.5], [0.0, -1.0]])

"""How agents move and never collide: lattice reservations, speed and acceleration limits.

An agent always holds the cell it is in plus the cells it has reserved ahead along one axis
(``ahead`` of them); it travels from its cell's centre toward the last reserved centre and
brakes so that it can always stop there. A cell is reserved only when it is free, so two
agents' squares can never overlap; `overlapping_pairs` checks that independently from positions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarmshape.errors import InputError

STEPS = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]], dtype=np.int64)
"""Direction index -> unit step; index 0 means "no direction"."""

FREE = -1
SEED = -2
WALL = -3
"""Occupancy codes besides agent indices (WALL: the ring of cells around the arena)."""

TOUCH = 1.0 - 1e-9
"""Squares whose centres are closer than this on both axes overlap; touching is allowed."""


@dataclass(frozen=True)
class Limits:
    """Kinematic limits in cells per step (speed) and cells per step squared (acceleration)."""

    max_speed: float = 0.5
    max_accel: float = 0.125

    def __post_init__(self) -> None:
        if not 0.0 < self.max_speed <= 1.0:
            raise InputError(f"max speed must be in (0, 1] cells per step, got {self.max_speed}")
        if not 0.0 < self.max_accel <= self.max_speed:
            raise InputError(f"max acceleration must be in (0, max speed], got {self.max_accel}")


def advance(offset: np.ndarray, speed: np.ndarray, ahead: np.ndarray, limits: Limits) -> np.ndarray:
    """Move every agent along its reserved run for one step; return how far each went.

    Speed rises by at most ``max_accel`` and is capped so that, braking at ``max_accel``, the
    agent stops by the last reserved centre (``ahead - offset`` away). Updates in place.
    """
    room = np.maximum(ahead - offset, 0.0)
    a = limits.max_accel
    # the largest v whose braking run v + (v - a) + (v - 2a) + ... still fits in `room`
    whole = np.floor((np.sqrt(1.0 + 8.0 * room / a) - 1.0) / 2.0)
    stop_cap = (room + a * whole * (whole + 1.0) / 2.0) / (whole + 1.0)
    step = np.minimum.reduce([np.full_like(speed, limits.max_speed), speed + a, stop_cap, room])
    step[ahead == 0] = 0.0
    offset += step
    speed[:] = step
    return step


def positions(cell: np.ndarray, direction: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Square centres in world units: cell centre plus progress toward the next cell."""
    return cell + 0.5 + offset[:, None] * STEPS[direction]


def resolve_claims(keys: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Among claims on the same cell key, pick one winner at random; return a winner mask."""
    shuffled = rng.permutation(len(keys))
    _, first = np.unique(keys[shuffled], return_index=True)
    wins = np.zeros(len(keys), dtype=bool)
    wins[shuffled[first]] = True
    return wins


def inside(cells: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    return (cells >= 0).all(axis=1) & (cells < np.array(size)).all(axis=1)


def overlapping_pairs(pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i, j)``, ``i != j``, of unit squares that overlap, without O(n^2) work.

    A spatial hash: overlapping squares have centres in the same or an adjacent cell, so
    agents are bucketed by the cell of their centre (a sort plus dense per-cell counts and
    starts) and each one tests only the buckets in half of its 3x3 neighbourhood.
    """
    n = len(pos)
    if n < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    cell = np.floor(pos).astype(np.int64)
    cell -= cell.min(axis=0) - 1  # a free ring of buckets around, so neighbours stay in range
    stride = int(cell[:, 1].max()) + 2
    key = cell[:, 0] * stride + cell[:, 1]
    count = np.bincount(key, minlength=(int(cell[:, 0].max()) + 2) * stride)
    start = np.cumsum(count) - count
    order = np.argsort(key, kind="stable")
    found_i, found_j = [], []
    for dx, dy in ((0, 0), (1, -1), (1, 0), (1, 1), (0, 1)):
        wanted = key + dx * stride + dy
        hits = count[wanted]
        i = np.repeat(np.arange(n), hits)
        rank = np.arange(len(i)) - np.repeat(np.cumsum(hits) - hits, hits)
        j = order[np.repeat(start[wanted], hits) + rank]
        keep = i < j if (dx, dy) == (0, 0) else np.ones(len(i), dtype=bool)
        keep &= np.abs(pos[i] - pos[j]).max(axis=1) < TOUCH
        found_i.append(i[keep])
        found_j.append(j[keep])
    return np.concatenate(found_i), np.concatenate(found_j)

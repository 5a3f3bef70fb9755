"""How agents move and never collide: lattice reservations, speed and acceleration limits.

An agent always holds the cell it is in plus the cells it has reserved ahead along one axis
(``ahead`` of them); it travels from its cell's centre toward the last reserved centre and
brakes so that it can always stop there. A cell is reserved only when it is free (see
`swarmshape.core.lattice`), so two squares never overlap; `swarmshape.core.audit` checks that.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from swarmshape.core.options import checked, option
from swarmshape.errors import SettingError

STEPS = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]], dtype=np.int64)
"""Direction index -> unit step (0 none, 1 east, 2 west, 3 south, 4 north; y down)."""
REVERSE = np.array([0, 2, 1, 4, 3])
"""The opposite of each direction index."""
RIGHT = np.array([0, 3, 4, 2, 1])
"""Each direction turned a quarter clockwise on screen: east -> south -> west -> north."""
LEFT = RIGHT[RIGHT[RIGHT]]
"""Each direction turned a quarter anticlockwise on screen."""
DIRECTION_OF = np.zeros((3, 3), dtype=np.int64)
DIRECTION_OF[STEPS[:, 0] + 1, STEPS[:, 1] + 1] = np.arange(len(STEPS))
"""The direction index of each unit step ``(dx, dy)``, at ``[dx + 1, dy + 1]``."""

SLOWEST = 0.001
"""Smallest speed and acceleration limit: a thousand steps a cell. Far smaller ones would only
make numbers underflow (a robot's braking distance becomes infinite)."""

TOUCH = 1.0 - 1e-9
"""Squares whose centres are closer than this on both axes overlap; touching is allowed."""


class Motion(Enum):
    """How a strategy's robots go to their targets, declared by the strategy.

    The modes differ in three rules of `swarmshape.core.steering`: whether a new mover plans a
    path, what a blocked mover does, and what its path may cross.
    """

    SWAP = "swap"
    """Many move at once: steer straight, swap targets with a settled robot in the way and pass
    targets round rings of robots waiting on each other (TSWAP); plan a path only around fixed
    obstacles (seeds, other groups' shapes)."""
    ROUTE = "route"
    """A few move at once (the paper's): plan a path around the other robots, and wait."""


@dataclass(frozen=True)
class Limits:
    """Kinematic limits in cells per step (speed) and cells per step squared (acceleration)."""

    max_speed: float = option(0.5, "cells per step", at_least=SLOWEST, at_most=1.0)
    max_accel: float = option(0.125, "cells per step squared", at_least=SLOWEST, at_most=1.0)

    def __post_init__(self) -> None:
        checked(self)
        if self.max_accel > self.max_speed:
            raise SettingError(
                "max_accel",
                f"must be at most max_speed ({self.max_speed:g}), got {self.max_accel:g}",
            )


def advance(offset: np.ndarray, speed: np.ndarray, ahead: np.ndarray, limits: Limits) -> np.ndarray:
    """Move every agent along its reserved run for one step; return how far each went.

    Speed rises by at most ``max_accel`` and is capped so that, braking at ``max_accel``, the
    agent stops by the last reserved centre (``ahead - offset`` away). Updates in place.
    """
    step = step_sizes(speed, np.maximum(ahead - offset, 0.0), limits)
    step[ahead == 0] = 0.0
    offset += step
    speed[:] = step
    return step


def step_sizes(
    speed: np.ndarray, room: np.ndarray, limits: Limits, pace: np.ndarray | None = None
) -> np.ndarray:
    """How far each robot goes this step: speed rises by at most ``max_accel`` up to its top
    speed (``max_speed``, times its `pace` if given), and is capped so that, braking at
    ``max_accel``, the robot stops within `room`. A room that never shrinks but by the robot's
    own motion (a fixed stopping point, or one moving ahead) never asks for harder braking."""
    a = limits.max_accel
    # the largest v whose braking run v + (v - a) + (v - 2a) + ... still fits in `room`
    whole = np.floor((np.sqrt(1.0 + 8.0 * room / a) - 1.0) / 2.0)
    stop_cap = (room + a * whole * (whole + 1.0) / 2.0) / (whole + 1.0)
    top = np.full_like(speed, limits.max_speed) if pace is None else limits.max_speed * pace
    return np.minimum.reduce([top, speed + a, stop_cap, room])


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

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
import numpy.typing as npt

from swarmshape.core.compiled import njit
from swarmshape.core.lattice import FREE
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
    pace = np.ones(len(speed)) if pace is None else pace
    return _step_sizes(speed, room, pace, limits.max_speed, limits.max_accel)


@njit
def _step_sizes(
    speed: np.ndarray, room: np.ndarray, pace: np.ndarray, top: float, a: float
) -> npt.NDArray[np.float64]:  # pragma: no cover (compiled)
    out = np.empty(len(speed))
    for i in range(len(speed)):
        out[i] = _step_size(speed[i], room[i], top * pace[i], a)
    return out


@njit
def _step_size(speed: float, room: float, top: float, a: float) -> float:  # pragma: no cover
    """One robot's step (see `step_sizes`)."""
    # the largest v whose braking run v + (v - a) + (v - 2a) + ... still fits in `room`
    whole: float = np.floor((np.sqrt(1.0 + 8.0 * room / a) - 1.0) / 2.0)
    stop_cap = (room + a * whole * (whole + 1.0) / 2.0) / (whole + 1.0)
    return min(top, speed + a, stop_cap, room)


@njit
def move(
    cell: np.ndarray, direction: np.ndarray, ahead: np.ndarray, offset: np.ndarray,
    speed: np.ndarray, distance: np.ndarray, pace: np.ndarray, leader: np.ndarray,
    holder: np.ndarray, queued: np.ndarray, stride: int, top: float, a: float,
) -> None:  # pragma: no cover (compiled)  # fmt: skip
    """Advance every robot along its reserved run (its arrays, updated in place); a robot
    reaching the next centre gives up the cell behind it (`holder` and `queued` by flat key) to
    the robot queued for it if there is one. Followers stay behind their leaders (`follow`)."""
    n = len(ahead)
    room, step = np.zeros(n), np.zeros(n)
    for r in range(n):
        if ahead[r] > 0:
            room[r] = max(ahead[r] - offset[r], 0.0)
            step[r] = _step_size(speed[r], room[r], top * pace[r], a)
    follow(cell, direction, offset, speed, pace, leader, room, step, top, a)
    for r in range(n):
        offset[r] += step[r]
        speed[r] = step[r]
        distance[r] += step[r]
    for r in range(n):
        if ahead[r] == 0 or offset[r] < TOUCH:
            continue
        key = (cell[r, 0] + 1) * stride + cell[r, 1] + 1
        taker = queued[key]
        holder[key], queued[key] = taker, FREE
        if taker >= 0:
            leader[taker] = -1
        cell[r, 0] += STEPS[direction[r], 0]
        cell[r, 1] += STEPS[direction[r], 1]
        ahead[r] -= 1
        offset[r] -= 1.0
        if ahead[r] == 0:
            offset[r], speed[r] = 0.0, 0.0


@njit
def follow(
    cell: np.ndarray, direction: np.ndarray, offset: np.ndarray, speed: np.ndarray,
    pace: np.ndarray, leader: np.ndarray, room: np.ndarray, step: np.ndarray, top: float,
    a: float,
) -> None:  # pragma: no cover (compiled)  # fmt: skip
    """Cap followers' steps so that each stays a whole cell behind its leader.

    A follower may go as far as its leader's trailing edge after the leader's own step, and
    plans to be able to stop there; a leader only moves on, so that never asks for harder
    braking. A follower goes the way its leader goes, so a train is a straight line led by a
    robot that follows nobody: taken from its head back, each link's step is worked out
    after its leader's, and a train of any length starts and stops as one, in one pass."""
    followers = np.flatnonzero(leader >= 0)
    lead = np.empty(len(followers))
    first = np.full(len(step), -1)  # per robot, its followers as a linked list through `then`
    then = np.empty(len(followers), dtype=np.int64)
    order = np.empty(len(followers), dtype=np.int64)  # links, each after its leader's link
    count = 0
    for k in range(len(followers)):
        f = followers[k]
        ahead_by = 0
        for axis in range(2):
            ahead_by += (cell[leader[f], axis] - cell[f, axis]) * STEPS[direction[f], axis]
        lead[k] = ahead_by + offset[leader[f]] - offset[f] - 1.0
        step[f] = 0.0
        then[k], first[leader[f]] = first[leader[f]], k
        if leader[leader[f]] < 0:  # first behind the train's head
            order[count] = k
            count += 1
    done = 0
    while done < count:
        k = order[done]
        done += 1
        f = followers[k]
        wall = max(lead[k] + step[leader[f]], 0.0)
        step[f] = _step_size(speed[f], min(room[f], wall), top * pace[f], a)
        behind = first[f]
        while behind >= 0:
            order[count] = behind
            count += 1
            behind = then[behind]


def positions(
    cell: npt.NDArray[np.int64], direction: npt.NDArray[np.int64], offset: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Square centres in world units: cell centre plus progress toward the next cell."""
    return cell + 0.5 + offset[:, None] * STEPS[direction]


def resolve_claims(keys: np.ndarray, rng: np.random.Generator, scratch: np.ndarray) -> np.ndarray:
    """Among claims on the same cell key, pick one winner at random; return a winner mask.
    `scratch` holds -1 for every key, and is left so (see `audit.new_scratch`)."""
    return _first_claims(keys, rng.permutation(len(keys)), scratch)


@njit
def _first_claims(
    keys: np.ndarray, shuffled: np.ndarray, scratch: np.ndarray
) -> npt.NDArray[np.bool_]:  # pragma: no cover (compiled)
    """The first claim on each key in `shuffled` order wins."""
    wins = np.zeros(len(keys), dtype=np.bool_)
    for claim in shuffled:
        if scratch[keys[claim]] < 0:
            scratch[keys[claim]] = claim
            wins[claim] = True
    for claim in shuffled:
        scratch[keys[claim]] = -1
    return wins


def rows(array: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``array[index]`` for a 2-D array of few columns (cells, targets), many times faster than
    indexing (numpy 2.4: 0.15 ms against 1.5 ms for 20,000 rows of two)."""
    return np.take(array, index, axis=0)


def inside(cells: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    return np.all(cells >= 0, axis=1) & np.all(cells < np.array(size), axis=1)

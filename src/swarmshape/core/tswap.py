"""The TSWAP rules for movers that block each other (Okumura and Defago, AIJ 2023).

Pure functions over robot indices and targets, so the rules can be tested on their own:

- a mover blocked by a settled robot of its group swaps targets with it (the settled robot moves
  on inward, the mover takes its cell), so a target walled in by others is passed inward;
- movers at rest that wait for each other in a ring pass their targets one step round the ring,
  which shortens every trip, so a deadlock cycle dissolves;
- and, from local task swapping, a mover trades targets with the mover it waits for when that
  shortens their trips.

Each blocker takes part in one trade per step (`one_per_blocker`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from swarmshape.core.compiled import njit
from swarmshape.core.motion import rows


def ring_members(waiting: np.ndarray, waited_for: np.ndarray, robots: int) -> np.ndarray:
    """Robots on rings of the "waits for" graph, where ``waiting[k]`` waits for ``waited_for[k]``
    (robot numbers below `robots`), in increasing order.

    Each robot waits for at most one other, so a walk from any waiting robot either runs out or
    runs into a ring; walks stop at robots an earlier walk went through, so each robot is
    visited once."""
    return _on_rings(waiting, waited_for, robots)


@njit
def _on_rings(
    waiting: np.ndarray, waited_for: np.ndarray, robots: int
) -> npt.NDArray[np.intp]:  # pragma: no cover (compiled)
    next_of = np.full(robots, -1)
    for k in range(len(waiting)):
        next_of[waiting[k]] = waited_for[k]
    seen = np.zeros(robots, dtype=np.int8)  # 1: on the current walk, 2: on an earlier one
    ring = np.zeros(robots, dtype=np.bool_)
    for start in waiting:
        robot = start
        while robot >= 0 and seen[robot] == 0:
            seen[robot] = 1
            robot = next_of[robot]
        if robot >= 0 and seen[robot] == 1:  # the walk closed a ring of its own
            member = robot
            while not ring[member]:
                ring[member] = True
                member = next_of[member]
        robot = start
        while robot >= 0 and seen[robot] == 1:
            seen[robot] = 2
            robot = next_of[robot]
    return np.flatnonzero(ring)


def rotate_rings(waiting: np.ndarray, waited_for: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(givers, receivers)``: on every ring, each robot hands its target to the robot it
    waits for.

    The robot waited for stands in the way to the waiting robot's target, one cell closer to
    it, so taking that target over shortens the trip (TSWAP's rotation).
    """
    if len(waiting) < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    robots = int(max(waiting.max(), waited_for.max())) + 1
    members = ring_members(waiting, waited_for, robots)
    waits_for = np.full(robots, -1)
    waits_for[waiting] = waited_for
    return members, waits_for[members]


def one_per_blocker(movers: np.ndarray, blockers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(movers, blockers)`` pairs that trade targets: each blocker with the first mover
    blocked by it, so no robot takes part in two trades in one step."""
    _, first = np.unique(blockers, return_index=True)
    return movers[first], blockers[first]


def shortening_swaps(
    waiting: np.ndarray,
    waited_for: np.ndarray,
    cell: np.ndarray,
    trip: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """``(waiting, waited_for)`` pairs of neighbours that should trade goals (local task
    swapping, Wang and Rubenstein, IEEE T-RO 2020): those where trading shortens their summed
    trips, or keeps them and brings the waiting robot nearer its goal. ``trip(robots, cells)``
    is how far each robot's goal lies from `cells`. Crossing lanes tangle into long chains of
    robots each waiting on the next, and crossing paths often tie; a trade usually sends both
    the way that is free. No robot is in two pairs."""
    at_waiting, at_waited_for = rows(cell, waiting), rows(cell, waited_for)
    own = trip(waiting, at_waiting)
    taken = trip(waited_for, at_waiting)
    now = own + trip(waited_for, at_waited_for)
    traded = taken + trip(waiting, at_waited_for)
    pairs = np.flatnonzero((traded < now) | ((traded == now) & (taken < own)))
    everyone = np.concatenate([waiting[pairs], waited_for[pairs]])
    once = np.bincount(everyone, minlength=len(cell))[everyone] == 1
    alone = once[: len(pairs)] & once[len(pairs) :]
    return waiting[pairs[alone]], waited_for[pairs[alone]]

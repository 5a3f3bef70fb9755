"""The TSWAP rules for movers that block each other (Okumura and Defago, AIJ 2023).

Pure functions over robot indices and targets, so the rules can be tested on their own:

- a mover blocked by a settled robot of its group swaps targets with it (the settled robot moves
  on inward, the mover takes its cell), so a target walled in by others is passed inward;
- movers at rest that wait for each other in a ring pass their targets one step round the ring,
  which shortens every trip, so a deadlock cycle dissolves.
"""

from __future__ import annotations

import numpy as np


def ring_members(waiting: np.ndarray, waited_for: np.ndarray, robots: int) -> np.ndarray:
    """Robots on rings of the "waits for" graph, where ``waiting[k]`` waits for ``waited_for[k]``.

    Pointer doubling: after more jumps than there are waiting robots every walk has either run
    out (-1) or is going round a ring, and the places the walks reach are the ring members.
    """
    next_of = np.full(robots + 1, -1)  # the extra last slot keeps -1 at -1
    next_of[waiting] = waited_for
    jump = next_of.copy()
    for _ in range(len(waiting).bit_length()):
        jump = jump[jump]
    reached = jump[waiting]
    return np.unique(reached[reached >= 0])


def rotate_rings(
    target: np.ndarray, waiting: np.ndarray, waited_for: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(receivers, targets)``: on every ring, each robot hands its target to the robot it
    waits for; apply with ``target[receivers] = targets``.

    The robot waited for stands in the way to the waiting robot's target, one cell closer to
    it, so taking that target over shortens the trip (TSWAP's rotation).
    """
    if len(waiting) < 2:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=target.dtype)
    members = ring_members(waiting, waited_for, len(target))
    waits_for = np.full(len(target), -1)
    waits_for[waiting] = waited_for
    return waits_for[members], target[members]


def settled_swaps(movers: np.ndarray, settled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(movers, settled)`` pairs that swap targets: each settled robot with the first mover
    blocked by it, so no robot takes part in two swaps in one step."""
    _, first = np.unique(settled, return_index=True)
    return movers[first], settled[first]


def shortening_swaps(
    waiting: np.ndarray, waited_for: np.ndarray, cell: np.ndarray, goal: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(waiting, waited_for)`` pairs of neighbours that should trade goals (local task
    swapping, Wang and Rubenstein, IEEE T-RO 2020): those where trading shortens their summed
    lattice distance, or keeps it and brings the waiting robot nearer its goal. Crossing lanes
    tangle into long chains of robots each waiting on the next, and crossing paths in lattice
    distance often tie; a trade usually sends both the way that is free. No robot is in two
    pairs."""

    def apart(robots: np.ndarray, goals: np.ndarray) -> np.ndarray:
        return np.abs(cell[robots] - goals).sum(axis=1)

    own = apart(waiting, goal[waiting])
    taken = apart(waiting, goal[waited_for])
    now = own + apart(waited_for, goal[waited_for])
    traded = taken + apart(waited_for, goal[waiting])
    pairs = np.flatnonzero((traded < now) | ((traded == now) & (taken < own)))
    everyone = np.concatenate([waiting[pairs], waited_for[pairs]])
    once = np.bincount(everyone, minlength=len(cell))[everyone] == 1
    alone = once[: len(pairs)] & once[len(pairs) :]
    return waiting[pairs[alone]], waited_for[pairs[alone]]

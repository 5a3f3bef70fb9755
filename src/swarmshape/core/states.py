"""What a robot is doing, one small int per robot so whole swarms are advanced with masks."""

from __future__ import annotations

from enum import IntEnum


class State(IntEnum):
    WAITING = 0
    """Has no target yet (waits for a message or an assignment)."""
    MOVING = 1
    """Heading for its target."""
    SETTLED = 2
    """On its target, for good unless a mover swaps with it."""
    WANDERING = 3
    """A spare robot walking at random outside the shape."""
    STALLED = 4
    """Failed where it stands (a dead motor): holds its cell for good, an obstacle to others."""
    LOST = 5
    """Removed by a fault: off the lattice, no longer part of the run (its index stays)."""


WAITING, MOVING, SETTLED, WANDERING, STALLED, LOST = (int(state) for state in State)
"""Plain ints for the hot loop: an IntEnum member lookup costs a microsecond each time."""

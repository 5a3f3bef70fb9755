"""A robot's perception as a fixed-size vector, and back.

Every robot's observation is one float32 row: first its own state, then ``K`` neighbour slots
(nearest first, as the robot senses them; unused slots are all zero with ``present`` 0)::

    own:        ready, cruising, heading, progress, moved_x, moved_y, number, group, step
    each slot:  present, dx, dy, seed, kin, heard, frame_x, frame_y, message_0 .. message_{k-1}

- ``ready``: at rest on a cell centre, so a move given now starts now, any way.
- ``cruising``: under way with its next cell reserved and no further: the action ``heading``
  (straight on) goes on without braking; any other action lets it brake and stop on that cell
  (a robot under way cannot turn). ``heading``: the move it is making (0 at rest);
  ``progress``: how far along it it has come from its cell's centre (0 to 1).
- ``moved_x, moved_y``: odometry, whole cells moved in the last step.
- ``number``: the robot's number in its group (a unique ID); ``group``: its group; ``step``.
- ``dx, dy``: the neighbour's centre relative to the robot's, in cells (noisy if the run has
  distance noise, clipped to the observation bounds); ``seed``: the neighbour is a seed;
  ``kin``: it is of the robot's group; ``heard``: its message came through this step.
- ``frame_x, frame_y``: a heard seed's cell in the seed frame (zero otherwise).
- ``message_*``: the neighbour's last broadcast where heard (zero otherwise).

All positions and moves are in the robot's seed-frame axes. With ``K`` at least the number of
cells within the sensing radius (the default) nothing a local program senses is dropped, and
`perception_of` rebuilds the `Perception` a program would have been given.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.perception import Blueprint, Perception

OWN = ("ready", "cruising", "heading", "progress", "moved_x", "moved_y", "number", "group",
       "step")  # fmt: skip
SLOT = ("present", "dx", "dy", "seed", "kin", "heard", "frame_x", "frame_y")
READY, CRUISING, HEADING, PROGRESS, MOVED_X, MOVED_Y, NUMBER, GROUP, STEP = range(len(OWN))
PRESENT, DX, DY, SEED, KIN, HEARD, FRAME_X, FRAME_Y = range(len(SLOT))


@dataclass(frozen=True)
class Layout:
    """Where each value sits in an observation row (see the module's description)."""

    neighbours: int
    """``K``: neighbour slots per robot."""
    message_size: int
    """Integers per broadcast."""
    radius: float
    """The sensing radius the slots were filled from (a program's `Perception.radius`)."""

    @property
    def slot_size(self) -> int:
        return len(SLOT) + self.message_size

    @property
    def size(self) -> int:
        return len(OWN) + self.neighbours * self.slot_size

    @property
    def names(self) -> list[str]:
        """Every entry's name, in order (``slot3.dx`` and so on)."""
        slot = [*SLOT, *(f"message_{i}" for i in range(self.message_size))]
        return [*OWN, *(f"slot{k}.{name}" for k in range(self.neighbours) for name in slot)]

    def own(self, obs: np.ndarray) -> np.ndarray:
        """The own-state part ``(..., len(OWN))`` of observations ``(..., size)`` (a view)."""
        return obs[..., : len(OWN)]

    def slots(self, obs: np.ndarray) -> np.ndarray:
        """The neighbour slots ``(..., K, slot_size)`` of observations (a view)."""
        return obs[..., len(OWN) :].reshape(*obs.shape[:-1], self.neighbours, self.slot_size)


def encode(sense: Perception, layout: Layout, bound: float | None = None) -> np.ndarray:
    """Every robot's observation ``(n, size)`` float32; offsets clipped to ``±bound`` if given
    (noise can carry them past any bound; without noise they stay within ``radius + 2``)."""
    n, k = len(sense), layout.neighbours
    obs = np.zeros((n, layout.size), dtype=np.float32)
    own = obs[:, : len(OWN)]
    own[:, READY] = sense.ready
    own[:, CRUISING] = sense.cruising
    own[:, HEADING] = sense.heading
    own[:, PROGRESS] = sense.progress
    own[:, MOVED_X : MOVED_Y + 1] = sense.moved
    own[:, NUMBER] = sense.number
    own[:, GROUP] = sense.group
    own[:, STEP] = sense.step
    clip = np.inf if bound is None else bound
    _fill_slots(
        obs, len(OWN), layout.slot_size, k, sense.start, sense.offset, clip, sense.seed,
        sense.kin, sense.heard, sense.seed_frame, sense.message,
    )  # fmt: skip
    return obs


@njit
def _fill_slots(
    obs: np.ndarray,
    first: int,
    size: int,
    k: int,
    start: np.ndarray,
    offset: np.ndarray,
    bound: float,
    seed: np.ndarray,
    kin: np.ndarray,
    heard: np.ndarray,
    seed_frame: np.ndarray,
    message: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """Each robot's first `k` entries into its slots, from column `first` on, `size` floats a
    slot. Laid out field by field and then moved slot by slot in numpy, they took the batched
    environment half its step with 1,000 robots packed (`scripts/bench_env.py`)."""
    limit = np.float32(bound)
    for r in range(len(start) - 1):
        for e in range(start[r], min(start[r + 1], start[r] + k)):
            at = first + (e - start[r]) * size
            obs[r, at + PRESENT] = 1.0
            obs[r, at + DX] = min(max(np.float32(offset[e, 0]), -limit), limit)
            obs[r, at + DY] = min(max(np.float32(offset[e, 1]), -limit), limit)
            obs[r, at + SEED] = seed[e]
            obs[r, at + KIN] = kin[e]
            obs[r, at + HEARD] = heard[e]
            obs[r, at + FRAME_X] = seed_frame[e, 0]
            obs[r, at + FRAME_Y] = seed_frame[e, 1]
            for m in range(message.shape[1]):
                obs[r, at + len(SLOT) + m] = message[e, m]


def perception_of(obs: np.ndarray, layout: Layout, blueprint: Blueprint) -> Perception:
    """The `Perception` that observations ``(n, size)`` encode (every robot's, in order), for
    programs written against the plug-in contract: with enough slots, the one they were made
    from, offsets rounded to float32."""
    own, slots = layout.own(obs), layout.slots(obs)
    present = slots[:, :, PRESENT] > 0
    owner, rank = np.nonzero(present)
    entries = slots[owner, rank].astype(np.float64)
    whole = np.rint(entries).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(present.sum(axis=1))]).astype(np.int64)
    return Perception(
        number=np.rint(own[:, NUMBER]).astype(np.int64),
        group=np.rint(own[:, GROUP]).astype(np.int64),
        ready=own[:, READY] > 0,
        heading=np.rint(own[:, HEADING]).astype(np.int64),
        cruising=own[:, CRUISING] > 0,
        progress=own[:, PROGRESS].astype(np.float64),
        moved=np.rint(own[:, MOVED_X : MOVED_Y + 1]).astype(np.int64),
        start=start,
        owner=owner.astype(np.int64),
        offset=entries[:, DX : DY + 1],
        seed=whole[:, SEED] > 0,
        kin=whole[:, KIN] > 0,
        heard=whole[:, HEARD] > 0,
        message=whole[:, len(SLOT) :],
        seed_frame=whole[:, FRAME_X : FRAME_Y + 1],
        blueprint=blueprint,
        step=int(own[0, STEP]) if len(obs) else 0,
        radius=layout.radius,
    )

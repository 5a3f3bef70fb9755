"""The learned baseline: one small linear policy shared by every robot, over features of its
own observation that do not depend on the swarm's size, so that parameters trained on 100
robots drive 10,000 unchanged.

Two layers. A fixed one, written by hand, turns each robot's observation into what it can
infer (`Sight`): where it is in the seed frame (from a heard seed, or from a neighbour at rest
that knows where it is and says so, carried between fixes by odometry), which cells around it
are taken, which shape cells it senses open, and the nearest open cell its neighbours relay (a
hop count, as a gradient). A learned one scores each of the five moves by a weighted sum of a
few features of that move (is its cell taken, does it enter the shape, go nearer the shape or
deeper into it, toward an open cell, straight on, into a crowd) and picks the best, with
Gumbel noise of a learned temperature to break ties and deadlocks. Its parameters are the 15
numbers in `WEIGHTS`; ``examples/learn_benchmark.py`` trains them.

A robot broadcasts `LINK`: whether it is a beacon (localised, at rest and staying, so next step
it is still on the cell it names), that cell, and the open shape cell it knows of with the hops
to the robot that saw it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy

from swarmshape.core.motion import LEFT, STEPS
from swarmshape.core.perception import Blueprint, Senses
from swarmshape.env.observe import (
    CRUISING,
    DX,
    DY,
    FRAME_X,
    FRAME_Y,
    GROUP,
    HEADING,
    HEARD,
    MOVED_X,
    MOVED_Y,
    PRESENT,
    PROGRESS,
    READY,
    SEED,
    SLOT,
    Layout,
)

LINK = ("beacon", "x", "y", "open", "open_x", "open_y", "hops")
"""What a robot broadcasts, in order."""
BEACON, X, Y, OPEN, OPEN_X, OPEN_Y, HOPS = range(len(LINK))
FIXED = 16
"""A beacon says where its centre will be in 1/16 cells."""
MESSAGE_RANGE = (-(2**20), 2**20 - 1)
"""Frame positions and hop counts, with room for arenas far larger than 10,000 robots need."""

RELAY_HOPS = 32
"""Hops an open cell is relayed. News of a cell filled since dies out by counting up to this
(each robot takes its neighbours' fewest hops plus one), so it bounds how stale news can be."""

MOVE_FEATURES = ("taken", "enters", "leaves", "nearer", "deeper", "edge", "to_open",
                 "to_relayed", "straight", "crowd")  # fmt: skip
STAY_FEATURES = ("bias", "on_shape", "lost", "braking")
WEIGHTS = (*(f"move.{name}" for name in MOVE_FEATURES),
           *(f"stay.{name}" for name in STAY_FEATURES), "log_temperature")  # fmt: skip
"""The policy's parameters, by name, in order."""

PARAMETERS = Path(__file__).with_name("learned.json")
"""The trained parameters the leaderboard uses."""


@dataclass(frozen=True)
class Fields:
    """Each group's shape as one lookup in its seed frame: how deep a cell inside lies
    (taxicab steps to the outside, >= 1) or how far a cell outside lies (as minus its
    taxicab distance to the shape, <= 0)."""

    boxes: tuple[tuple[np.ndarray, np.ndarray], ...]
    """Per group: the frame cell of its grid's corner, and the grid, with a one-cell border
    outside the shape (a cell off the grid is as far as the border cell nearest it, plus
    its taxicab distance to that cell: exact, as the shape lies inside the border)."""

    @classmethod
    def of(cls, blueprint: Blueprint) -> Fields:
        boxes = []
        for cells in blueprint.cells:
            low = cells.min(axis=0) - 1
            grid = np.zeros(cells.max(axis=0) - low + 2, dtype=bool)
            grid[cells[:, 0] - low[0], cells[:, 1] - low[1]] = True
            depth = scipy.ndimage.distance_transform_cdt(grid, metric="taxicab")
            outside = scipy.ndimage.distance_transform_cdt(~grid, metric="taxicab")
            boxes.append((low, np.where(grid, depth, -outside).astype(np.int64)))
        return cls(tuple(boxes))

    def signed(self, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
        """The value of each frame cell ``(k, 2)`` in the shape of its group ``(k,)``."""
        value = np.zeros(len(frame), dtype=np.int64)
        for group, (low, grid) in enumerate(self.boxes):
            mine = np.flatnonzero(groups == group) if len(self.boxes) > 1 else slice(None)
            local = frame[mine] - low
            clipped = np.clip(local, 0, np.array(grid.shape) - 1)
            beyond = np.abs(local - clipped).sum(axis=1)
            value[mine] = grid[clipped[:, 0], clipped[:, 1]] - beyond
        return value


class Sight:
    """What every robot infers from its observations, step by step (the hand-written layer):
    its frame cell, the cells around it taken, the shape round it, the open shape cells it
    senses, and the open cell relayed to it."""

    def __init__(self, layout: Layout, blueprint: Blueprint, robots: int) -> None:
        self.layout = layout
        self.fields = Fields.of(blueprint)
        self.reach = Senses(radius=layout.radius).reach()
        self.half = math.ceil(layout.radius) + 1
        """Half the side of the window of cells a sensed robot may overlap."""
        self.side = 2 * self.half + 1
        block = np.argwhere(np.ones((3, 3), dtype=bool)) - 1
        self.near = np.unique(np.concatenate([block, self.reach]), axis=0)
        """Cells whose place in the shape a robot looks up: the 3x3 block round it (its
        moves and what lies beside them) and every cell it senses."""
        self.column = np.full(self.side * self.side, -1, dtype=np.int64)
        self.column[self.slot(self.near)] = np.arange(len(self.near))
        """The column in `near` of each window slot."""
        self.sensed = self.column[self.slot(self.reach)]
        self.known = np.zeros(robots, dtype=bool)
        self.cell = np.zeros((robots, 2), dtype=np.int64)
        self.centre = np.zeros((robots, 2))

    def slot(self, offsets: np.ndarray) -> np.ndarray:
        """Window slots of cell offsets ``(k, 2)`` within `half`."""
        return (offsets[:, 0] + self.half) * self.side + (offsets[:, 1] + self.half)

    def at(self, offsets: np.ndarray) -> np.ndarray:
        """Columns in `near` of cell offsets ``(k, 2)``."""
        return self.column[self.slot(offsets)]

    def update(self, obs: np.ndarray) -> None:
        """Take in one step's observations ``(n, size)``."""
        own, slots = self.layout.own(obs), self.layout.slots(obs)
        self.group = np.rint(own[:, GROUP]).astype(np.int64)
        self.ready = own[:, READY] > 0
        self.cruising = own[:, CRUISING] > 0
        self.heading = np.rint(own[:, HEADING]).astype(np.int64)
        along = own[:, PROGRESS, None] * STEPS[self.heading]  # from its cell's centre
        present = slots[:, :, PRESENT] > 0
        heard = present & (slots[:, :, HEARD] > 0)
        seed = present & (slots[:, :, SEED] > 0)
        message = slots[:, :, len(SLOT) :]
        offset = slots[:, :, DX : DY + 1].astype(np.float64)
        self._localise(own, along, offset, slots, message, heard & seed, heard & ~seed)
        self._see_taken(present, offset, along)
        self._look_at_the_shape()
        self._relay(message, heard & ~seed)

    def _localise(self, own, along, offset, slots, message, seeds, talking) -> None:
        """Odometry, then a fix from every heard seed and beacon: where it is less the offset
        is where I am. A localised robot is a beacon when it is at rest or was localised a
        step ago too: it says where its centre will be next step, if it goes on as in the
        last (speed changes by at most max_accel a step: an eighth of a cell by default)."""
        known = self.known
        self.cell[known] += np.rint(own[known, MOVED_X : MOVED_Y + 1]).astype(np.int64)
        beacons = talking & (message[:, :, BEACON] > 0)
        named = np.where(seeds[:, :, None], slots[:, :, FRAME_X : FRAME_Y + 1] + 0.5,
                         message[:, :, X : Y + 1] / FIXED)  # fmt: skip
        fixes = (named - offset) * (seeds | beacons)[:, :, None]
        count = (seeds | beacons).sum(axis=1)
        fixed = count > 0
        centre = fixes[fixed].sum(axis=1) / count[fixed, None]
        self.cell[fixed] = np.rint(centre - 0.5 - along[fixed]).astype(np.int64)
        self.known = known | fixed
        now = self.cell + 0.5 + along
        self.next_centre = np.where(known[:, None], 2 * now - self.centre, now)
        self.centre = now
        self.beacon = self.known & (known | self.ready)

    def _see_taken(self, present: np.ndarray, offset: np.ndarray, along: np.ndarray) -> None:
        """The window cells each sensed square overlaps (its own cell and the one ahead are
        the robot's own)."""
        n = len(present)
        rows, entries = np.nonzero(present)
        where = offset[rows, entries] + along[rows]
        low = np.floor(where).astype(np.int64)
        high = low + (where > low)
        taken = np.zeros((n, self.side * self.side), dtype=bool)
        half = self.half
        xs = [np.clip(low[:, 0], -half, half), np.clip(high[:, 0], -half, half)]
        ys = [np.clip(low[:, 1], -half, half), np.clip(high[:, 1], -half, half)]
        for x in xs:
            for y in ys:
                taken[rows, (x + half) * self.side + (y + half)] = True
        taken[np.arange(n), self.slot(STEPS[self.heading])] = False
        taken[:, self.slot(STEPS[:1])] = False
        self.taken = taken[:, self.slot(self.near)]

    def _look_at_the_shape(self) -> None:
        """The shape round every localised robot, and the deepest open cell it senses (the
        nearest of those)."""
        n, width = len(self.known), len(self.near)
        around = (self.cell[:, None, :] + self.near[None, :, :]).reshape(-1, 2)
        signed = self.fields.signed(np.repeat(self.group, width), around).reshape(n, width)
        signed[~self.known] = 0
        self.signed = signed
        look = signed[:, self.sensed]
        open_here = ~self.taken[:, self.sensed] & (look >= 1)
        rank = np.where(open_here, look * 64 - np.abs(self.reach).sum(axis=1), -(2**40))
        self.sees = open_here.any(axis=1)
        self.seen = self.reach[rank.argmax(axis=1)]  # relative to its own cell

    def _relay(self, message: np.ndarray, talking: np.ndarray) -> None:
        """The open cell it sees, or the one its neighbours relay with the fewest hops."""
        n = len(self.known)
        hops = np.where(talking & (message[:, :, OPEN] > 0), message[:, :, HOPS], np.inf)
        nearest = hops.argmin(axis=1)
        fewest = hops[np.arange(n), nearest] + 1
        told = (fewest <= RELAY_HOPS) & self.known
        heard_cell = np.rint(message[np.arange(n), nearest][:, OPEN_X : OPEN_Y + 1])
        self.open = self.sees | told
        self.hops = np.where(self.sees, 0, np.where(told, fewest, 0)).astype(np.int64)
        self.open_cell = np.where(self.sees[:, None], self.cell + self.seen,
                                  heard_cell.astype(np.int64))  # fmt: skip

    def move_features(self) -> np.ndarray:
        """``(n, 4, len(MOVE_FEATURES))``: each move's features (see `MOVE_FEATURES`)."""
        known = self.known[:, None]
        steps = STEPS[1:]
        here = self.signed[:, self.at(STEPS[:1])]
        there = self.signed[:, self.at(steps)]
        inside = here >= 1
        to_seen = np.sign(self.seen @ steps.T) * self.sees[:, None]
        relay = self.open & ~self.sees
        to_relayed = np.sign((self.open_cell - self.cell) @ steps.T) * relay[:, None]
        return np.stack(
            [
                self.taken[:, self.at(steps)],
                known & ~inside & (there >= 1),
                known & inside & (there < 1),
                known & ~inside & (there > here),
                np.where(known & inside & (there >= 1), np.sign(there - here), 0),
                known & ~inside & (there < 1) & self.wall_on_the_left(),
                to_seen,
                to_relayed,
                self.cruising[:, None] & (self.heading[:, None] == np.arange(1, 5)),
                self.crowd(steps),
            ],
            axis=-1,
        ).astype(np.float64)

    def wall_on_the_left(self) -> np.ndarray:
        """Per move, whether the shape or a sensed robot lies on the robot's left as it goes
        (beside it, or beside the cell it goes to): following such a wall walks round the
        shape, or round a crowd at its edge, all robots the same way."""
        wall = (self.signed >= 1) | self.taken
        left = STEPS[LEFT[1:]]
        return wall[:, self.at(left)] | wall[:, self.at(STEPS[1:] + left)]

    def crowd(self, steps: np.ndarray) -> np.ndarray:
        """Per move, the share of the cells in sensing range on that side that are taken."""
        side = (self.reach @ steps.T) > 0  # (reach, 4)
        taken = self.taken[:, self.sensed].astype(np.float64)
        return taken @ side / side.sum(axis=0)

    def stay_features(self) -> np.ndarray:
        """``(n, len(STAY_FEATURES))``."""
        on_shape = self.signed[:, self.at(STEPS[:1])[0]] >= 1
        return np.column_stack(
            [np.ones(len(self.known)), on_shape, ~self.known, self.cruising]
        ).astype(np.float64)

    def message(self) -> np.ndarray:
        """Every robot's broadcast ``(n, len(LINK))``."""
        centre = np.where(self.beacon[:, None], np.rint(self.next_centre * FIXED), 0)
        open_cell = np.where(self.open[:, None], self.open_cell, 0)
        said = np.column_stack([self.beacon, centre, self.open, open_cell, self.hops])
        return np.clip(said, *MESSAGE_RANGE).astype(np.int64)


class Learned:
    """The learned baseline as a benchmark policy (see the module's description)."""

    message_size = len(LINK)
    message_range = MESSAGE_RANGE

    def __init__(self, weights: Any = None, name: str = "learned") -> None:
        values = load_weights() if weights is None else np.asarray(weights, dtype=np.float64)
        if values.shape != (len(WEIGHTS),):
            raise ValueError(f"a learned policy takes {len(WEIGHTS)} weights, got {values.shape}")
        self.weights = values
        self.name = name
        self.sight: Sight | None = None

    def reset(self, context: Any) -> None:
        self.sight = Sight(context.layout, context.blueprint, context.robots)
        self.rng = context.rng()

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        sight = self.sight
        sight.update(obs)
        w = self.weights
        moves = len(MOVE_FEATURES)
        go = sight.move_features() @ w[:moves]
        stay = sight.stay_features() @ w[moves : moves + len(STAY_FEATURES)]
        scores = np.column_stack([stay, go])
        scores += math.exp(w[-1]) * self.rng.gumbel(size=scores.shape)
        chosen = scores.argmax(axis=1)
        return np.column_stack([chosen, sight.message()])


def load_weights(path: Path = PARAMETERS) -> np.ndarray:
    """The trained weights saved by ``examples/learn_benchmark.py``, in `WEIGHTS` order."""
    saved = json.loads(path.read_text(encoding="utf-8"))
    return np.array([saved["weights"][name] for name in WEIGHTS], dtype=np.float64)

"""Carrying the last empty cells of a full shape to the robots still outside it.

In the paper a robot covers a disc of cells, so a few cells left empty deep inside a formed
shape do not matter. On the lattice, with a robot per cell, each one must be filled, by a
robot that is still outside, often far off at the rim: an empty cell (a hole) must travel
through the robots in place to it. It travels when a robot beside it moves in, leaving its own
cell empty; unbiased, that is a random walk, and holes within sight of each other cancel each
other's mean shift.

So each robot inside its shape keeps its hops to the nearest robot waiting outside, through
robots inside it, side by side (a relay: 0 for a robot beside one outside), and a robot moves
into a hole only if that brings the hole no farther from them: its own hops are at most those
of the hole, one more than the least of the other robots beside it (0 if a robot outside is
beside it). A move that brings the hole nearer is always made; one that keeps it as far only
when the mean shift draws the robot that way.

A robot outside that senses no empty cell, beside the shape with its rim full (or at another
piece of it), follows news of an empty rim cell that robots inside see with nobody outside in
sight of it (another relay), round the shape (`swarmshape.strategies.routes`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Perception
from swarmshape.strategies.skills import relay, shape
from swarmshape.strategies.skills.view import View

NEAR = 3
"""Half-width of the cells round a robot whose neighbours it must know to judge a move: its
base is a step from its cell, the cell it moves into another, and that cell's neighbours one
more. (To judge the cells it senses, one more than its view's reach.)"""


class Around:
    """Who stands round each robot, as grids of cells ``(n, 2 reach + 1, 2 reach + 1)`` centred
    on its own cell (`reach`: `NEAR`, or one cell past the view's reach if that is more): the
    hops (to a robot waiting outside) of each robot inside the shape that it hears (`NONE`
    elsewhere), and where a robot of its group stands outside the shape, itself too if it is
    `outside`. Silent robots (stalled) are no one's way out, so only robots heard count. A
    robot inside seen beside one outside is 0 hops from it whatever it last said: its count
    is a step old, and the two may have come together since."""

    def __init__(
        self,
        sense: Perception,
        frame: np.ndarray,
        said: SimpleNamespace,
        view: View,
        outside: np.ndarray,
    ) -> None:
        self.reach = c = max(NEAR, view.reach + 1)
        n, side = len(sense), 2 * c + 1
        owner, rel = sense.owner, view.cells
        self.kin = sense.heard & sense.kin & ~sense.seed
        near = self.kin & (np.abs(rel) <= c).all(axis=1)
        cells = frame[owner] + rel
        self.inside = sense.blueprint.contains(sense.group[owner], cells)
        """Per entry: whether the neighbour stands on a cell of the shape."""
        self.hops = np.full((n, side, side), relay.NONE, dtype=np.int64)
        self.outside = np.zeros((n, side, side), dtype=bool)
        mark = near & self.inside & (said.localised == 1)
        self.hops[owner[mark], rel[mark, 0] + c, rel[mark, 1] + c] = relay.heard(
            said.to_waiting[mark]
        )
        self.there = np.zeros((n, side, side), dtype=bool)
        """Where a robot inside the shape stands that passes holes on."""
        self.there[owner[mark], rel[mark, 0] + c, rel[mark, 1] + c] = True
        mark = near & ~self.inside
        self.outside[owner[mark], rel[mark, 0] + c, rel[mark, 1] + c] = True
        self.outside[outside, c, c] = True
        beside = np.zeros_like(self.outside)
        beside[:, 1:] |= self.outside[:, :-1]
        beside[:, :-1] |= self.outside[:, 1:]
        beside[:, :, 1:] |= self.outside[:, :, :-1]
        beside[:, :, :-1] |= self.outside[:, :, 1:]
        self.hops[beside & self.there] = 0
        self.beside = (np.abs(rel).sum(axis=1) == 1) & self.kin
        """Per entry: a neighbour heard on a cell beside the robot's."""

    def via(self, robots: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The hops to the waiting robots of a hole passed on through who stands on each
        robot's cell at `cells` (relative to its own cell): 0 for a robot outside, one more
        than the hops of one inside, beyond any count for nobody; and whether one inside
        stands there."""
        x, y = (cells + self.reach).T
        hops = np.where(self.outside[robots, x, y], 0, self.hops[robots, x, y] + 1)
        return hops, self.there[robots, x, y]


def waiting_hops(
    sense: Perception,
    said: SimpleNamespace,
    around: Around,
    inside: np.ndarray,
    localised: np.ndarray,
    cap: int,
) -> np.ndarray:
    """Each robot's hops to the nearest robot outside its shape through robots inside it, side
    by side (`relay.NONE`: none known, or the robot is not inside)."""
    outside_beside = np.zeros(len(sense), dtype=bool)
    outside_beside[sense.owner[around.beside & ~around.inside]] = True
    source = inside & localised & outside_beside
    passes = around.beside & around.inside & (said.localised == 1)
    none = np.zeros((len(sense.owner), 0)), np.zeros((len(sense), 0))
    told = relay.heard(said.to_waiting)
    hops, _ = relay.relay(sense, passes, told, none[0], source, none[1], cap)
    return np.where(inside & localised & (hops < cap), hops, relay.NONE)


def hole_distance(around: Around, base: np.ndarray, cap: int) -> np.ndarray:
    """``(n, 4)``: for each way a robot could move from its base, the hops of a hole on that
    cell to the nearest robot waiting outside, counting every robot beside it but this one
    (capped at `cap`)."""
    n = len(base)
    rows = np.arange(n)
    distance = np.full((n, len(STEPS) - 1), cap, dtype=np.int64)
    for d, step in enumerate(STEPS[1:]):
        cell = base + step
        for beside in STEPS[1:]:
            there = cell + beside
            other = (there != base).any(axis=1)
            via = around.via(rows, there)[0]
            distance[:, d] = np.where(other, np.minimum(distance[:, d], via), distance[:, d])
    return np.minimum(distance, cap)


def coming(around: Around, offsets: np.ndarray) -> np.ndarray:
    """``(n, k)``: for each robot and each cell at window `offsets`, whether a robot inside the
    shape beside that cell, were it a hole, would move into it to bring it nearer the waiting
    robots (its hops are fewer than the hole's through the others beside it; see
    `hole_distance`). A robot outside leaves such a hole to come to it: chasing it, it steps
    where the hole was as the hole steps to where the robot was, both for ever."""
    n, k = len(around.hops), len(offsets)
    rows = np.repeat(np.arange(n), k)
    beside = [around.via(rows, np.tile(offsets + step, (n, 1))) for step in STEPS[1:]]
    via = np.stack([hops for hops, _ in beside], axis=1)  # (n k, 4): through each one beside
    filled = np.zeros(n * k, dtype=bool)
    for j, (hops, inside) in enumerate(beside):
        filled |= inside & (hops <= relay.NONE) & (hops - 1 < np.delete(via, j, axis=1).min(axis=1))
    return filled.reshape(n, k)


def open_news(
    sense: Perception,
    frame: np.ndarray,
    said: SimpleNamespace,
    around: Around,
    free: np.ndarray,
    offsets: np.ndarray,
    view: View,
    cap: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Each robot's hops to a robot that sees a cell no robot will fill unless one comes for
    it, and that cell: an empty rim cell (beside the outside, `shape.depth` 1) with nobody
    beside it, whom it could pass to as a hole or who could step into it. `free` ``(n, k)``
    marks the empty shape cells each robot senses at window `offsets`. News of a cell a robot
    sees taken is stale, and it does not pass it on."""
    n, k = free.shape
    cells = (frame[:, None, :] + offsets[None]).reshape(-1, 2)
    rim = shape.depth(sense.blueprint, np.repeat(sense.group, k), cells).reshape(n, k) == 1
    r = view.reach
    alone = np.ones((n, k), dtype=bool)
    for step in STEPS[1:]:
        beside = offsets + step
        seen = (np.abs(beside) <= r).all(axis=1)
        x, y = np.clip(beside + r, 0, 2 * r).T
        alone &= ~(view.taken[:, x, y] & seen[None])
    wanted = free & rim & alone
    distance = np.abs(offsets).sum(axis=1)
    nearest = np.argmin(np.where(wanted, distance[None], np.iinfo(np.int64).max), axis=1)
    found = frame + offsets[nearest]
    source = sense.blueprint.contains(sense.group, frame) & wanted.any(axis=1)
    stale = view.at(sense.owner, said.news - frame[sense.owner])[0]
    fresh = around.kin & (said.localised == 1) & ~stale
    return relay.relay(sense, fresh, relay.heard(said.news_hops), said.news, source, found, cap)

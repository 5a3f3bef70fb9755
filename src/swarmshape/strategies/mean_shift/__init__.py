"""`mean-shift`: mean-shift exploration on the lattice, after G. Sun, R. Zhou, Z. Ma, Y. Li,
R. Gross, Z. Chen and S. Zhao, "Mean-shift exploration in shape assembly of robot swarms",
Nature Communications 14:3476 (2023), doi:10.1038/s41467-023-39251-5.

Every robot knows the shape and senses only its neighbours within `--sense-radius` cells.
Each step a robot:

1. works out where it is from the seeds and its neighbours (`skills.localise`); one that cannot
   yet walks toward those that can;
2. outside its shape, heads down its grey level, the moves to the shape round the seeds (the
   paper's *entering* command), with a weight that falls as it comes near (`explore.entering`);
3. adds the paper's *exploration* command: the mean shift toward the unoccupied shape cells it
   senses, weighed by a raised-cosine kernel (`explore.mean_shift`);
4. moves one cell the way that sum points most, among the cells it may enter: a robot inside
   the shape stays inside it and enters only cells that bring the empty cell it leaves behind
   no farther from the robots still outside (`holes`); a robot outside that can reach an empty
   shape cell it senses takes only moves that bring it nearer one (`explore.nearer`), and
   leaves alone a hole that a robot inside is bringing to it (`holes.coming`);
5. keeps going without braking while the same move is still its choice from the cell it is
   coming to (cruising).

A robot at rest on a shape cell counts as in place; it moves again only to fill a hole beside
it. What differs from the continuous original, and why:

- **No negotiation.** The paper's robots agree on the shape's position and heading by
  consensus seeded by a fifth of them, the informed robots. Here the seeds are the informed
  robots: they never move and say their frame cells, and robots take theirs from them or from a
  neighbour that knows its own, so every robot holds the same frame, with no consensus error.
- **No repulsion.** The paper keeps robots apart with a repulsive and an aligning command; on
  the lattice two robots never share a cell and a move has no inertia. A robot is the paper's
  avoidance distance across, so an occupied cell is the paper's occupied footprint. What
  damps the paper's robots (their velocity lag, repulsion sliding them round each other)
  becomes the rule that a robot outside moves only nearer the empty cells it can reach: a
  straight pull toward their mean, blocked by a robot standing still, flipped it between two
  cells for ever.
- **Moves, not velocities.** The summed command picks one of four moves; inside the shape a move
  toward the unoccupied cells is made only when their mean lies at least `tau` cells that way.
- **Grey levels round the seeds.** The paper's grey image falls one level a cell toward the
  shape; here the levels count moves round the seeds, which stand beside the shape and
  would hold a robot beyond them pushing against them for ever.
- **Hole transport.** The paper's coverage counts a cell covered within a robot's avoidance
  distance, so a full shape needs no exact tiling. With a robot per cell, the last empty cells
  must travel through the robots in place to those still outside (`holes`); on its own the
  mean shift leaves them wandering deep inside. The paper's shape is one piece; robots at its
  full rim follow news of an empty cell elsewhere, so separate pieces form too.

Counts relayed hop by hop stop at twice the shape's cell count (no path through the swarm is
longer); the kernel reaches one cell past the sensing radius; every other constant is the
paper's or an option.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from swarmshape.core.local import Memory, Program, Schema, Slot
from swarmshape.core.motion import STEPS
from swarmshape.core.options import option
from swarmshape.core.perception import Perception
from swarmshape.strategies import register, routes
from swarmshape.strategies.mean_shift import explore, holes
from swarmshape.strategies.skills import relay
from swarmshape.strategies.skills.localise import FIXED, find_the_others, localise
from swarmshape.strategies.skills.view import View

MESSAGE = Schema(
    localised=1, cell=2, stays=1, heading=1, progress=1, to_waiting=1, news=2, news_hops=1,
)  # fmt: skip
"""What a robot broadcasts: whether it knows where it is, its frame cell, whether it stays on it
next step, the way it is moving and how far along (see `skills.localise`); its hops to a robot
waiting outside the shape (`holes.waiting_hops`); an empty rim cell it has news of and its hops
to the robot that sees it (`holes.open_news`). Counts are said as `relay.said` puts them (0:
none)."""

LOST, OUTSIDE, INSIDE, IN_PLACE = range(4)


@register
class MeanShift(Program):
    name = "mean-shift"
    description = "entering and mean shift toward unoccupied cells sensed (Sun et al. 2023)"
    message_size = len(MESSAGE)
    states = ("lost", "outside the shape", "inside, moving", "in place")
    shown = "to_waiting"
    memory: ClassVar[dict[str, Slot]] = {
        "state": Slot(np.int64, LOST),
        "localised": Slot(bool, False),
        "frame": Slot(np.int64, 0, 2),
        "roam": Slot(np.int64, 0),
        "to_waiting": Slot(np.int64, relay.NONE),
        "news": Slot(np.int64, 0, 2),
        "news_hops": Slot(np.int64, relay.NONE),
        "in_place": Slot(bool, False),
    }

    @dataclass(frozen=True)
    class Options:
        entering: float = option(
            10.0, "gain of the entering command (the paper's k1)", at_least=0.0
        )
        exploring: float = option(
            15.0, "gain of the mean shift (the paper's k2, its code's exploration term)",
            at_least=0.0,
        )  # fmt: skip
        band: float = option(
            3.0,
            "cells round the shape over which the entering command fades to nothing (the "
            "paper's grey band, 3.2 to 3.6 robot spacings in its shapes)",
            at_least=1.0,
        )
        tau: float = option(
            0.5,
            "cells the mean shift must reach along a move for a robot inside the shape to make "
            "it when it brings no hole nearer the robots outside",
            at_least=0.0,
        )
        roam: float = option(
            1.0,
            "how long a robot that sees nobody localised walks straight on average before it "
            "turns at random, in steps per cell of its shape's longer side (it turns at a wall "
            "too)",
            at_least=0.0,
        )

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        said = MESSAGE.read(sense.message)
        group, blueprint = sense.group, sense.blueprint
        cap = 2 * sum(len(cells) for cells in blueprint.cells)
        options = self.options
        localise(sense, memory, said)
        localised, frame = memory.localised, memory.frame
        kin = sense.heard & sense.kin & ~sense.seed
        view = View(sense, int(sense.radius), np.where(kin, said.heading, 0))
        offset = explore.base(sense)
        base = frame + offset
        inside = blueprint.contains(group, base)
        window = explore.Window(sense.radius)
        on_shape = localised & blueprint.contains(group, frame)
        around = holes.Around(sense, frame, said, view, localised & ~on_shape)
        coming = holes.coming(around, window.offsets)
        outside = localised & ~inside
        shift, free = explore.mean_shift(sense, frame, view, window, offset, outside, coming)
        sees = free.any(axis=1)
        memory.to_waiting = holes.waiting_hops(sense, said, around, on_shape, localised, cap)
        memory.news_hops, memory.news = holes.open_news(
            sense, frame, said, around, free, window.offsets, view, cap
        )
        pull = explore.entering(sense, base, options.band)
        command = options.exploring * shift + np.where(
            inside[:, None], 0.0, options.entering * pull
        )
        rows = np.flatnonzero(localised & ~inside & ~sees & (memory.news_hops < cap))
        way, found = routes.waypoints(
            blueprint, group[rows], base[rows], memory.news[rows], int(sense.radius)
        )
        rows = rows[found]
        command[rows] = options.entering * explore.unit(way[found] - base[rows])
        rows = np.flatnonzero(outside & sees)
        toward = np.zeros((len(sense), len(STEPS) - 1), dtype=bool)
        toward[rows] = explore.nearer(view.taken[rows], offset[rows], free[rows], window.offsets)
        moves = self._moves(sense, memory, view, around, offset, inside, command, toward, cap)
        span = max(int(np.ptp(cells, axis=0).max()) + 1 for cells in blueprint.cells)
        turn_every = max(1, round(options.roam * span))
        lost = find_the_others(sense, memory, said, view, turn_every, rng)
        moves = np.where(localised, moves, lost)
        stays = sense.ready & (moves == 0)
        memory.in_place = on_shape & stays
        memory.state = np.select(
            [~localised, memory.in_place, on_shape], [LOST, IN_PLACE, INSIDE], OUTSIDE
        )
        heading = np.where(moves > 0, moves, sense.heading)
        messages = MESSAGE.pack(
            localised=localised,
            cell=frame,
            stays=stays,
            heading=np.where(stays, 0, heading),
            progress=np.rint(sense.progress * FIXED),
            to_waiting=relay.said(memory.to_waiting, cap),
            news=memory.news,
            news_hops=relay.said(memory.news_hops, cap),
        )
        return moves, messages

    def _moves(
        self,
        sense: Perception,
        memory: Memory,
        view: View,
        around: holes.Around,
        offset: np.ndarray,
        inside: np.ndarray,
        command: np.ndarray,
        toward: np.ndarray,
        cap: int,
    ) -> np.ndarray:
        """Each robot's move: the way its command points most among the cells it may enter
        from its base (see the module's description); under way, on straight ahead or none.
        A robot outside that can reach an empty shape cell it senses moves only `toward` it
        ``(n, 4)`` (see `explore.nearer`)."""
        n = len(sense)
        ways = STEPS[1:]
        into = offset[:, None, :] + ways[None]
        taken = view.at(np.repeat(np.arange(n), len(ways)), into.reshape(-1, 2))[0]
        cells = (memory.frame[:, None, :] + into).reshape(-1, 2)
        in_shape = sense.blueprint.contains(np.repeat(sense.group, len(ways)), cells)
        open_ = ~taken.reshape(n, -1)
        distance = holes.hole_distance(around, offset, cap)
        mine = np.minimum(memory.to_waiting, cap)[:, None]
        score = command @ ways.T
        outward = open_ & np.where(toward.any(axis=1)[:, None], toward, score > 0)
        closer = open_ & in_shape.reshape(n, -1) & (mine < distance)
        level = open_ & in_shape.reshape(n, -1) & (mine == distance)
        level &= score >= self.options.tau * self.options.exploring
        inward = np.where(closer.any(axis=1)[:, None], closer, level)
        allowed = np.where(inside[:, None], inward, outward)
        best = 1 + np.argmax(np.where(allowed, score, -np.inf), axis=1)
        moves = np.where(allowed.any(axis=1) & memory.localised, best, 0)
        moves[sense.cruising & (moves != sense.heading)] = 0
        moves[~sense.ready & ~sense.cruising] = 0
        return moves

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
        return memory.localised.copy(), memory.frame.copy()

    def finished(self, memory: Memory) -> np.ndarray:
        """Robots at rest on a cell of their shape (one may move again to fill a hole)."""
        return memory.in_place.copy()

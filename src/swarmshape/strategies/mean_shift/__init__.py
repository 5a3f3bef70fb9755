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
   the shape stays inside it and enters only cells deeper in it than its own, so that the
   empty cell it leaves lies nearer the robots outside, and one in place enters only a cell
   they cannot reach (`holes`), or, when a robot waits in a pocket the shape encloses, one
   that carries a hole nearer to it (`holes.pulled`), or, on the rim, one that stalled
   robots wall off from them (`holes.unwalled`); a robot outside that can reach an empty
   shape cell it senses takes only moves that bring it nearer one (`explore.nearer`); toward
   an empty cell of a piece that only pockets touch, a robot steps across the pocket
   (`holes.across_pockets`);
5. keeps going without braking while the same move is still its choice from the cell it is
   coming to (cruising);
6. outside, with robots in every way it wants for more than `patience` steps, steps to a free
   cell at random (`MeanShift._moves`).

A robot at rest on a shape cell counts as in place; it moves again only to carry a hole
beside it out. What differs from the continuous original, and why:

- **No negotiation.** The paper's robots agree on the shape's position and heading by
  consensus seeded by a fifth of them, the informed robots. Here the seeds are the informed
  robots: they never move and say their frame cells, and robots take theirs from them or from a
  neighbour that knows its own, so every robot holds the same frame, with no consensus error.
- **No repulsion.** The paper keeps robots apart with a repulsive and an aligning command; on
  the lattice two robots never share a cell and a move has no inertia, but two robots can
  stand in each other's way for good, so a robot kept waiting steps aside. A robot is the paper's
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
  must travel out through the robots in place to those still outside (`holes`); on its own the
  mean shift leaves them wandering deep inside. The paper's shape is one piece; robots at its
  full rim follow news of an empty cell elsewhere, and one that hears of no robot sensing an
  empty cell walks the shape's rim cells in turn (`MeanShift._tour`), so separate pieces form
  too, however far apart.

Counts relayed hop by hop, and news a robot keeps, stop after a lap of the shape's rim at a
robot's pace (`lap_pace`): news older than that is of a cell long filled. At twice the shape's
cell count (no path through the swarm is longer) robots followed such news for hundreds of
steps: the 299-robot K took 2,271 steps, and 1,178 with the lap. Word that a news cell is
taken travels the same way, so that news is dropped as soon as it is stale, not a lap later
(`holes.open_news`). The kernel reaches one cell past the sensing radius, and a rim hole that
robots it does not hear have walled off for ten steps in a row counts as walled off by stalled
ones (`skills.view.SILENCE`, as `local-swap` and `self-assembly` count); every other constant
is the paper's or an option.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import ClassVar

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.local import Memory, Program, Schema, Slot
from swarmshape.core.motion import SLOWEST, STEPS
from swarmshape.core.options import option
from swarmshape.core.perception import Perception
from swarmshape.strategies import register, routes
from swarmshape.strategies.mean_shift import explore, holes
from swarmshape.strategies.skills import relay, shape
from swarmshape.strategies.skills.localise import FIXED, anchor_said, find_the_others, localise
from swarmshape.strategies.skills.view import View

MESSAGE = Schema(
    localised=1, cell=2, stays=1, heading=1, progress=1, anchor=1, news=2, news_hops=1,
    gone_cell=2, gone_age=1, pull=1, seen=1,
)  # fmt: skip
"""What a robot broadcasts: whether it knows where it is, its frame cell, whether it stays on it
next step, the way it is moving and how far along, and its hops to the seeds through robots at
rest (see `skills.localise`); an empty rim cell it
has news of and its hops to the robot that sees it, a cell it has word is taken and how old
that word is (`holes.open_news`); its hops to a robot
waiting in a pocket of the shape (`holes.pulled`), and its hops to a robot that sees an
empty cell of the shape (`MeanShift._tour`), counts said as `relay.said` puts them (0:
none)."""

LOST, OUTSIDE, INSIDE, IN_PLACE = range(4)


@register
class MeanShift(Program):
    name = "mean-shift"
    description = "entering and mean shift toward unoccupied cells sensed (Sun et al. 2023)"
    enters_from_outside = True
    message_size = len(MESSAGE)
    states = ("lost", "outside the shape", "inside, moving", "in place")
    shown = "news_hops"
    memory: ClassVar[dict[str, Slot]] = {
        "state": Slot(np.int64, LOST),
        "localised": Slot(bool, False),
        "frame": Slot(np.int64, 0, 2),
        "anchor": Slot(np.int64, relay.NONE),
        "roam": Slot(np.int64, 0),
        "news": Slot(np.int64, 0, 2),
        "news_hops": Slot(np.int64, relay.NONE),
        "gone": Slot(np.int64, 0, 2),
        "gone_age": Slot(np.int64, relay.NONE),
        "in_place": Slot(bool, False),
        "tour": Slot(np.int64, -1),
        "toured": Slot(np.int64, 0),
        "waited": Slot(np.int64, 0),
        "walled": Slot(np.int64, 0, 4, added=True),
        "rounding": Slot(np.int64, 0, added=True),
        "facing": Slot(np.int64, 0, added=True),
        "hit": Slot(np.float64, np.inf, added=True),
        "round_to": Slot(np.int64, 0, 2, added=True),
    }

    _around: shape.Around | None = None
    """The last step's `shape.Around`, whose squares the next one takes over where robots
    stood still."""

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
            "cells the mean shift must reach along a move for a robot on its way in to enter a "
            "cell that robots outside can reach too",
            at_least=0.0,
        )
        lap_pace: float = option(
            2.0,
            "steps a robot takes per cell at its top speed (2 at the default half a cell a "
            "step): news of an empty rim cell lives, and a robot follows it, for as long as a "
            "lap of the shape's rim takes at that pace",
            at_least=0.0,
            at_most=1 / SLOWEST,  # a thousand steps a cell: the slowest a robot can be made
        )
        patience: int = option(
            5,
            "steps a robot outside waits with every move it wants blocked before it steps "
            "to a free cell at random (5: the steps to cross a cell from rest at the default "
            "limits, by when a robot in front that makes way has left it)",
            at_least=1,
        )
        roam: int = option(
            20,
            "a robot that sees nobody localised turns at random once in this many steps under "
            "way, on average (and at a wall or a robot in its way)",
            at_least=1,
        )

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        said = MESSAGE.read(sense.message)
        group, blueprint = sense.group, sense.blueprint
        options = self.options
        cap = max(1, math.ceil(options.lap_pace * shape.rim(blueprint)))
        localise(sense, memory, said)
        localised, frame = memory.localised, memory.frame
        kin = sense.heard & sense.kin & ~sense.seed
        view = View(sense, int(sense.radius), np.where(kin, said.heading, 0))
        offset = explore.base(sense)
        base = frame + offset
        # the view's square, a cell round it for its cells' neighbours, and at least the two
        # cells' reach of a move and the cell beside that (`_moves`)
        around = shape.Around(blueprint, group, frame, max(int(sense.radius) + 1, 3), self._around)
        self._around = around
        inside = around.contains(offset)
        window = explore.window(sense.radius)
        on_shape = localised & blueprint.contains(group, frame)
        outside = localised & ~inside
        shift, free = explore.mean_shift(sense, around, view, window, offset, outside)
        sees = explore.any_per_row(free)
        memory.news_hops, memory.news, memory.gone, memory.gone_age = holes.open_news(
            sense, frame, around, said, free, window.offsets, view, memory, cap
        )
        rows = np.flatnonzero(~inside)  # the command is for those outside only
        pull = np.zeros((len(sense), 2))
        pull[rows] = explore.entering(blueprint, group[rows], base[rows], options.band)
        command = options.exploring * shift + np.where(
            inside[:, None], 0.0, options.entering * pull
        )
        heard = localised & ~inside & ~sees & (memory.news_hops < cap)
        waiting = outside & ~sees & around.enclosed(offset)
        speaks = kin & (said.localised == 1)
        seen = self._hops(sense, speaks, said.seen, localised & sees, localised, cap)
        quiet = outside & ~sees & ~waiting & ~heard & (seen >= cap)
        touring = self._tour(sense, memory, base, quiet)
        rows = np.flatnonzero(heard | touring)
        goal = np.where(heard[rows, None], memory.news[rows], shape.tour(
            blueprint, group[rows], memory.tour[rows])[0])  # fmt: skip
        way, found = routes.waypoints(blueprint, group[rows], base[rows], goal, int(sense.radius))
        rows, way, goal = rows[found], way[found], goal[found]
        command[rows] = options.entering * explore.unit(way - base[rows])
        toward = np.zeros((len(sense), len(STEPS) - 1), dtype=bool)
        memory.facing = np.where(sense.heading > 0, sense.heading, memory.facing)
        following = np.zeros(len(sense), dtype=bool)
        following[rows] = options.entering > 0
        memory.rounding[~following] = 0
        if options.entering > 0:
            toward[rows] = explore.round_the_silent(
                sense, memory, view, around, window, rows, way, goal, rng
            )
        rows = np.flatnonzero(outside & sees)
        walls = explore.seeded(view.taken_of(rows), frame[rows])
        toward[rows] = explore.nearer(walls, offset[rows], free[rows], window.offsets)
        pull = self._hops(sense, speaks, said.pull, waiting, on_shape | waiting, cap)
        across = np.zeros_like(toward)
        if around.any_sealed:
            in_pocket = outside & around.enclosed(offset)
            rows = np.flatnonzero(localised & (memory.in_place | in_pocket))
            across[rows] = holes.across_pockets(
                sense, said, view, around, frame, offset, free, window.offsets, rows
            )
        moves = self._moves(
            sense, memory, said, view, around, offset, inside, command, toward, across, pull,
            cap, rng,
        )  # fmt: skip
        lost = find_the_others(sense, memory, said, view, options.roam, rng)
        moves = np.where(localised, moves, lost)
        stays = sense.ready & (moves == 0)
        # in place until it moves: a move asked for and not made (the cell taken first) leaves
        # it where it was, and out of place it would go on to carry open holes (`holes`)
        memory.in_place = on_shape & sense.ready & (stays | memory.in_place)
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
            anchor=anchor_said(sense, memory),
            news=memory.news,
            news_hops=relay.said(memory.news_hops, cap),
            gone_cell=memory.gone,
            gone_age=relay.said(memory.gone_age, cap),
            pull=relay.said(pull, cap),
            seen=relay.said(seen, cap),
        )
        return moves, messages

    @staticmethod
    def _tour(sense: Perception, memory: Memory, base: np.ndarray, quiet: np.ndarray) -> np.ndarray:
        """Which robots walk the shape's tour (`shape.tour`) to find an empty cell that no
        robot within a lap's hops senses (a piece of the shape beyond the sensing radius of
        every robot): `quiet` ones outside (seeing no empty cell, hearing of none) that stand
        beside the shape, from the tour cell nearest them, once round. Each goes on to
        the next tour cell as soon as it senses this one; one that sees or hears of an empty
        cell starts over when it next has none."""
        blueprint, group = sense.blueprint, sense.group
        memory.tour[~quiet] = -1
        starts = quiet & (memory.tour < 0) & (explore.grey(blueprint, group, base) == 1)
        memory.tour[starts] = shape.nearest_on_tour(blueprint, group[starts], base[starts])
        memory.toured[starts] = 0
        rows = np.flatnonzero(quiet & (memory.tour >= 0))
        while len(rows):
            cell, length = shape.tour(blueprint, group[rows], memory.tour[rows])
            on = memory.toured[rows] < length
            on &= np.hypot(*(cell - base[rows]).T) <= sense.radius
            rows = rows[on]
            memory.tour[rows] = (memory.tour[rows] + 1) % length[on]
            memory.toured[rows] += 1
        rows = np.flatnonzero(quiet & (memory.tour >= 0))
        touring = np.zeros(len(sense), dtype=bool)
        touring[rows] = (
            memory.toured[rows] < shape.tour(blueprint, group[rows], memory.tour[rows])[1]
        )
        return touring

    @staticmethod
    def _hops(
        sense: Perception,
        heard: np.ndarray,
        counts: np.ndarray,
        sources: np.ndarray,
        relays: np.ndarray,
        cap: int,
    ) -> np.ndarray:
        """Each robot's hops to the nearest of `sources`, from the `counts` its neighbours
        said (per entry; those `heard`), passed on by `relays` only: `cap` (none) for the
        others. Robots waiting in a pocket pull through robots on the shape, who alone can
        carry a hole to them (`holes.pulled`). With no source and no count said, as in a shape
        with no pocket, none is heard: the relay is skipped."""
        if not sources.any() and not counts.any():
            return np.full(len(sense), cap, dtype=np.int64)
        told = np.zeros((len(sense.owner), 0), dtype=np.int64)
        found = np.zeros((len(sense), 0), dtype=np.int64)
        hops, _ = relay.relay(sense, heard, relay.heard(counts), told, sources, found, cap)
        return np.where(relays, hops, cap)

    def _moves(
        self,
        sense: Perception,
        memory: Memory,
        said: SimpleNamespace,
        view: View,
        around: shape.Around,
        offset: np.ndarray,
        inside: np.ndarray,
        command: np.ndarray,
        toward: np.ndarray,
        across: np.ndarray,
        pull: np.ndarray,
        cap: int,
        rng: np.random.Generator,
    ) -> np.ndarray:
        """Each robot's move: the way its command points most among the cells it may enter
        from its base (see the module's description); under way, on straight ahead or none.
        A robot outside that can reach an empty shape cell it senses moves only `toward` it
        ``(n, 4)`` (see `explore.nearer`); one inside that hears a `pull` only carries holes
        toward the pocket it comes from (`holes.pulled`): drawn back into the cell it left, it
        would carry the hole back again. A robot with a way `across` pockets to an empty cell
        of a piece that only pockets touch takes it (`holes.across_pockets`), in place or not.

        A robot outside at rest with robots in every way it wants for more than `patience`
        steps on end steps to a free cell at random. Two robots going round the shape the
        opposite ways met head-on and each waited for the other for good: on the 529-robot K
        every robot outside stood still from step 200 to 300."""
        n = len(sense)
        ways = STEPS[1:]
        into = np.empty((n, len(ways), 2), dtype=np.int64)
        open_, in_shape, deeper = (np.empty((n, len(ways)), dtype=bool) for _ in range(3))
        _entered(view.bordered_taken, view.reach, around.inside, around.depths, around.reach,
                 offset, into, open_, in_shape, deeper)  # fmt: skip
        score = command @ ways.T
        toward = np.where((~inside & explore.any_per_row(across))[:, None], across, toward)
        wanted = np.where(explore.any_per_row(toward)[:, None], toward, score > 0)
        outward = open_ & wanted
        # a hole robots coming in can reach is theirs; a robot on its way in takes one too
        # when the mean shift draws it there; a robot coming in beside a hole keeps it, and
        # one waiting in a pocket pulls the others
        pulling = inside & (pull < cap)
        asked = deeper | (open_ & in_shape & pulling[:, None])
        met, empty = holes.open_holes(sense, around, said, view, into, asked)
        drawn = ~memory.in_place[:, None] & (score >= self.options.tau * self.options.exploring)
        inward = deeper & (~(met | empty) | drawn)
        inward |= holes.unwalled(sense, memory, around, said, view, offset, open_ & in_shape)
        to_pocket = open_ & in_shape & ~met
        to_pocket &= holes.pulled(sense, said, view, into, pull, cap)
        inward[pulling] = to_pocket[pulling]
        off_shape = open_ & ~in_shape & across
        crossing = explore.any_per_row(off_shape)
        inward[crossing] = off_shape[crossing]
        allowed = np.where(inside[:, None], inward, outward)
        best = 1 + np.argmax(np.where(allowed, score, -np.inf), axis=1)
        moves = np.where(explore.any_per_row(allowed) & memory.localised, best, 0)
        moves[sense.cruising & (moves != sense.heading)] = 0
        moves[~sense.ready & ~sense.cruising] = 0
        kept_waiting = memory.localised & ~inside & sense.ready & ~sense.cruising
        kept_waiting &= explore.any_per_row(wanted) & ~explore.any_per_row(outward)
        memory.waited = np.where(kept_waiting, memory.waited + 1, 0)
        rows = np.flatnonzero(memory.waited > self.options.patience)
        aside = np.where(open_[rows], rng.random((len(rows), len(ways))), -1.0)
        moves[rows] = np.where(aside.max(axis=1) >= 0, 1 + aside.argmax(axis=1), 0)
        return moves

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
        return memory.localised.copy(), memory.frame.copy()

    def finished(self, memory: Memory) -> np.ndarray:
        """Robots at rest on a cell of their shape (one may move again to fill a hole)."""
        return memory.in_place.copy()


@njit
def _entered(
    taken: np.ndarray,
    sight: int,
    inside: np.ndarray,
    depth: np.ndarray,
    reach: int,
    base: np.ndarray,
    into: np.ndarray,
    open_: np.ndarray,
    in_shape: np.ndarray,
    deeper: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """Per robot and move from its `base`, the cell it enters (`into`): whether it senses it
    free (`View`'s bordered squares, `sight` cells either way, beyond them free), whether it
    lies in its shape, and whether it is free and deeper in it than the base (`Around`'s
    squares, `reach` cells either way). As numpy lookups over every robot, 1.8 ms of a
    10,000-robot step, and numpy's sums of bases and moves, four pairs a robot, 0.4 ms."""
    last = 2 * sight + 2
    for robot in range(len(base)):
        bx, by = base[robot, 0], base[robot, 1]
        here = depth[robot, bx + reach, by + reach]
        for j in range(len(STEPS) - 1):
            x, y = bx + STEPS[j + 1, 0], by + STEPS[j + 1, 1]
            into[robot, j, 0], into[robot, j, 1] = x, y
            vx, vy = min(max(x + sight + 1, 0), last), min(max(y + sight + 1, 0), last)
            open_[robot, j] = not taken[robot, vx, vy]
            in_shape[robot, j] = inside[robot, x + reach, y + reach]
            there = depth[robot, x + reach, y + reach]
            deeper[robot, j] = open_[robot, j] and in_shape[robot, j] and there > here

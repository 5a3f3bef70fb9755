"""`self-assembly`: programmable self-assembly (M. Rubenstein, A. Cornejo, R. Nagpal,
"Programmable self-assembly in a thousand-robot swarm", Science 345(6198):795-799, 2014,
doi:10.1126/science.1254295), ported to the cell lattice.

Every robot runs the same program with the paper's states (plus `wander`, for robots that start
alone, and `stopped`, for one that walked round everything without finding a place). Robots in
the paper start packed against the seeds; a wanderer, scattered away from them, walks straight
on until it hears the structure (`localise.roam`), then heads for it.

- **gradient**: a stationary robot's value is one more than the least value among its 4-adjacent
  stationary neighbours (seeds hold 0), spread by messages one hop per step;
- **localisation**: a robot at rest next to seeds or joined robots takes, from each of them, its
  broadcast position less the sensed (noisy) offset, and moves its estimate a quarter of the way
  to their mean (the paper's iterative trilateration, with the bearing a lattice compass gives);
  positions are floats, rounded to a cell only to look the bitmap up; odometry carries the
  estimate between fixes;
- **leaving one at a time**: a waiting robot starts to move only when no moving robot is within
  sensing range and its gradient is greater than every non-joined neighbour's (ties: the higher
  ID); a robot that has lately missed messages waits for that ``lossy_patience`` steps in a row
  (so a lost message rarely lets it go beside a mover), others at once;
- **edge-following**: a right-hand wall follower around the stationary robots (turn right,
  straight, left, back; the next cell must touch a stationary robot), waiting behind a moving
  robot in its way; every follower keeps them on its right, so all go round one way (one
  that stepped back to let another pass turns round again); under way, a follower works out
  what it would do on the cell it is coming to and goes on without braking when that is
  straight on (the paper's robots glide; on the lattice stopping on every cell cost 2.5 times
  the steps);
- **joining**: once its estimate lies in the shape, a robot stops for good when its next move
  would leave the shape, or when a 4-adjacent joined robot has a gradient at least its own (the
  end of the layer being built); on the lattice, also at a dead end (walls ahead and on both
  hands), and not where it would wall free cells of the shape off (`_pockets`, `_onward`: it
  moves on into them instead), nor, while a follower beside it that goes first might stop
  too, where their two stops would (it waits for that one).

As in the paper, shapes with holes cannot be formed (the runner warns), and errors in gradient
and position warp the shape more the farther it grows from the seeds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from swarmshape.core.local import Memory, Program, Schema, Slot
from swarmshape.core.motion import LEFT, REVERSE, RIGHT, STEPS
from swarmshape.core.options import option
from swarmshape.core.perception import Blueprint, Perception
from swarmshape.strategies import register
from swarmshape.strategies.skills.localise import roam
from swarmshape.strategies.skills.view import SILENCE, distances

START, WAIT, WANDER, OUTSIDE, INSIDE, JOINED, STOPPED = range(7)
STATES = ("start", "wait", "wander", "outside", "inside", "joined", "stopped")
STATIONARY = (START, WAIT, JOINED, STOPPED)

MESSAGE = Schema(state=1, gradient=1, localised=1, position=2, number=1, want=1)
"""What a robot broadcasts: its state plus one (0 is a robot that has not spoken yet),
gradient, whether it is localised, its position estimate in 1/`FIXED` cells, its ID, and the
direction a blocked follower waits to move in (0 if none)."""

FIXED = 1024
INFINITE = 1 << 23
"""The gradient of a robot connected to no seed: above any hop count, and below 2**24, so that
the broadcast holds exactly in a learning environment's float32 observation."""

NEVER = 1 << 30
"""Steps since a robot last missed a message, for one that never has."""


# The 5x5 window around a robot, row-major over dy then dx, each -2..2; slot 12 is its own cell.
WINDOW = np.array([(dx, dy) for dy in range(-2, 3) for dx in range(-2, 3)], dtype=np.int64)
SELF = 12


def _slot(step: np.ndarray) -> np.ndarray:
    """The window slot of offsets ``(k, 2)`` within two cells."""
    return (step[..., 1] + 2) * 5 + (step[..., 0] + 2)


AROUND = np.array([[_slot(STEPS[d] + WINDOW[s] - WINDOW[SELF]) for s in (6, 7, 8, 11, 13, 16,
                   17, 18)] for d in range(5)])  # fmt: skip
"""``[d]``: the window slots of the 8 cells around the cell one step in direction d (the
robot's own cell among them for d > 0)."""
BORDER = (np.abs(WINDOW) == 2).any(axis=1)
"""Per window slot, whether it is on the window's outer ring."""
NEAR8 = np.array([6, 7, 8, 11, 13, 16, 17, 18])
"""The window slots of the 8 cells around the robot."""
TOUCHING = np.isin(np.arange(25), NEAR8)
"""Per window slot, whether it is one of `NEAR8`."""
AHEAD = _slot(STEPS)
"""``[d]``: the window slot of the cell one step in direction d (the robot's own for 0)."""
RIGHT_SIDE = _slot(STEPS[RIGHT])
"""``[d]``: the window slot of the cell on the right of a robot heading d."""
FRONT_RIGHT = _slot(STEPS + STEPS[RIGHT])
"""``[d]``: the window slot of the cell ahead and to the right of a robot heading d."""
HANDS = {
    name: np.stack([_slot(STEPS[hand] + along) for along in (0 * STEPS, STEPS, STEPS[REVERSE])], 1)
    for name, hand in (("right", RIGHT), ("left", LEFT))
}
"""``[hand][d]``: the window slots of the three cells on that hand of a robot heading d (beside
it, ahead and behind)."""


@register
class SelfAssembly(Program):
    name = "self-assembly"
    description = "gradient, localisation and edge-following (Rubenstein, Cornejo & Nagpal 2014)"
    message_size = len(MESSAGE)
    states = STATES
    grows_from_seeds = True
    shown = "gradient"

    @dataclass(frozen=True)
    class Options:
        startup: int = option(4, "steps a robot only listens before it may act", at_least=0)
        patience: int = option(
            1,
            "steps in a row a waiting robot must find itself first in line before it leaves, "
            "when every neighbour's message arrives (a robot that left is heard moving the "
            "next step)",
            at_least=1,
        )
        lossy_patience: int = option(
            8,
            "the same for a robot that has lately missed a neighbour's message: a moving "
            "neighbour must go unheard this many steps in a row before it trusts that none is "
            "near (at 10 % loss three lost messages in a row let a robot leave beside a mover)",
            at_least=1,
        )
        loss_memory: int = option(
            20, "steps a robot remembers that it missed a neighbour's message", at_least=0
        )
        alone: int = option(
            150,
            "steps a waiting robot with no gradient waits before it walks off at random to "
            "find one",
            at_least=0,
        )
        roam: int = option(
            20,
            "a wanderer that hears nothing of the structure turns at random once in this many "
            "steps under way, on average (and at a wall or a robot in its way)",
            at_least=1,
        )

    memory: ClassVar[dict[str, Slot]] = {
        "state": Slot(np.int64, START),
        "gradient": Slot(np.int64, INFINITE),
        "localised": Slot(bool, False),
        "position": Slot(np.float64, 0.0, 2),
        "heading": Slot(np.int64, 0),
        "age": Slot(np.int64, 0),
        "eligible": Slot(np.int64, 0),
        "since_loss": Slot(np.int64, NEVER),
        "travelled": Slot(np.int64, 0),
        "want": Slot(np.int64, 0),
        "known": Slot(np.int64, -1, 25),
        "unheard": Slot(np.int64, 0, 25, added=True),
        "roam": Slot(np.int64, 0, added=True),
        "held": Slot(np.int64, 0, added=True),
    }

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        n = len(sense)
        moved = (sense.moved != 0).any(axis=1)
        memory.age += 1
        _odometry(sense, memory, moved)
        state = memory.state
        state[(state == START) & (memory.age > self.options.startup)] = WAIT
        following = (state == OUTSIDE) | (state == INSIDE)
        near = _Near(sense, following & sense.cruising)
        rows = _busy(near, memory)
        _settled_gradient(near, memory, rows)
        _localise(sense, memory)
        moves = np.zeros(n, dtype=np.int64)
        if len(rows):
            view = _View(near, sense, memory, moved, rows)
            mine = _Rows(memory, rows)
            moved_rows = np.zeros(len(rows), dtype=np.int64)
            _gradient(view, mine)
            _leave(view, mine, self.options)
            _follow(view, _Where(sense, rows), mine, moved_rows)
            _arrive(view, mine, moved_rows)
            _home_in(view, mine, moved_rows, rng)
            mine.write_back()
            moves[rows] = moved_rows
            moves += _roam(sense, memory, view, rows, moved_rows, self.options.roam, rng)
        messages = MESSAGE.pack(
            state=memory.state + 1,
            gradient=memory.gradient,
            localised=memory.localised,
            position=np.rint(memory.position * FIXED),
            number=sense.number,
            want=memory.want,
        )
        return moves, messages

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
        return memory.localised.copy(), _frame_cell(memory)

    def finished(self, memory: Memory) -> np.ndarray:
        return (memory.state == JOINED) | (memory.state == STOPPED)


class _Near:
    """Each robot's neighbours within two cells of where it decides from, decoded once a
    step: the window slot each lies in, whether it sits on a cell centre, and what it said
    (its state, -1 unheard). The robots `coming` (edge-followers under way, see `_follow`)
    decide from the cell they are coming to, the others from where they are."""

    def __init__(self, sense: Perception, coming: np.ndarray) -> None:
        self.coming = coming
        ahead = (1 - sense.progress[:, None]) * np.take(STEPS, sense.heading, axis=0)
        ahead[~coming] = 0.0
        offset = sense.offset - np.take(ahead, sense.owner, axis=0)
        ox, oy = offset[:, 0], offset[:, 1]
        e = np.flatnonzero((np.abs(ox) < 2.5) & (np.abs(oy) < 2.5))
        self.entries = e
        self.me = sense.owner[e]
        ox, oy = ox[e], oy[e]
        self.cx, self.cy = np.rint(ox).astype(np.int64), np.rint(oy).astype(np.int64)
        self.fx, self.fy = ox - self.cx, oy - self.cy
        self.centred = (np.abs(self.fx) < 0.35) & (np.abs(self.fy) < 0.35)
        self.slot = (self.cy + 2) * 5 + (self.cx + 2)
        self.kin = sense.kin[e]
        self.seed = sense.seed[e] & self.kin  # another group's seeds are only obstacles
        said = MESSAGE.read(np.take(sense.message, e, axis=0))  # `LocalControl.perceive` (1)
        state = said.state - 1
        self.spoke = sense.heard[e] & self.kin & ~self.seed & (state >= 0)
        self.state = state
        self.stays = (state <= WAIT) | (state >= JOINED)
        self.first = said.number < sense.number[self.me]  # it goes first in a tie
        self.unblocked = said.want == 0
        self.gradient = np.minimum(said.gradient, INFINITE)
        n = len(sense)
        touching = TOUCHING[self.slot]
        self.crowded = np.bincount(self.me[touching], minlength=n) >= 8
        want = said.want
        # a moving neighbour that waits to step into the robot's own cell
        asking = np.flatnonzero(self.spoke & ~self.stays & (want > 0) & (want < len(STEPS)))
        aim = STEPS[want[asking]]
        self.facing = np.zeros(len(e), dtype=bool)
        self.facing[asking] = (self.cx[asking] == -aim[:, 0]) & (self.cy[asking] == -aim[:, 1])
        unheard = ~sense.heard & sense.kin & ~sense.seed
        self.missed = np.bincount(sense.owner[unheard], minlength=n) > 0


def _busy(near: _Near, memory: Memory) -> np.ndarray:
    """The robots with something to decide: all but the joined, the stopped, and waiting
    robots hemmed in on all eight sides (they cannot leave; only their gradient changes)."""
    state = memory.state
    resting = (state == JOINED) | (state == STOPPED)
    resting |= ((state == WAIT) | (state == START)) & near.crowded
    memory.known[resting] = -1
    memory.unheard[resting] = 0
    memory.eligible[resting] = 0
    memory.since_loss = np.where(near.missed, 0, memory.since_loss + 1)
    return np.flatnonzero(~resting)


def _settled_gradient(near: _Near, memory: Memory, rows: np.ndarray) -> None:
    """The gradient of robots not in `rows` (all stationary): the least of their own and one
    more than each touching stationary neighbour heard this step (see `_gradient`)."""
    n = len(memory)
    idle = np.ones(n, dtype=bool)
    idle[rows] = False
    use = idle[near.me] & TOUCHING[near.slot] & near.centred
    use &= (near.spoke & near.stays) | near.seed
    value = np.where(near.seed[use], 0, near.gradient[use])
    least = np.full(n, INFINITE, dtype=np.int64)
    np.minimum.at(least, near.me[use], value)
    offer = np.where(least >= INFINITE, INFINITE, least + 1)
    memory.gradient[idle] = np.minimum(memory.gradient[idle], offer[idle])


class _Rows:
    """A program's memory for some robots only (`rows`), written back by `write_back`."""

    def __init__(self, memory: Memory, rows: np.ndarray) -> None:
        self._memory, self._rows = memory, rows
        for name in memory.slots:
            setattr(self, name, getattr(memory, name)[rows])

    def __len__(self) -> int:
        return len(self._rows)

    def write_back(self) -> None:
        for name in self._memory.slots:
            getattr(self._memory, name)[self._rows] = getattr(self, name)


class _Where:
    """The parts of a `Perception` that `_follow` reads, for robots `rows` only."""

    def __init__(self, sense: Perception, rows: np.ndarray) -> None:
        self.group = sense.group[rows]
        self.heading = sense.heading[rows]
        self.blueprint = sense.blueprint
        self.rows = len(rows)

    def __len__(self) -> int:
        return self.rows


class _View:
    """What each robot of `rows` knows of the 5x5 cells around it: ``taken`` (something
    there), ``stationary`` (a seed, or a robot that stays and has a gradient: the structure, a
    wall to follow), ``mover`` (a robot heard moving), ``rival`` (an edge-follower at rest,
    its way free, that goes first in a tie: a lower number), ``joined`` and their
    ``gradient``. Stationary neighbours heard before stay known while the robot has not moved
    and their cell stays taken, so a lost message does not hide a wall; ``unknown`` cells are
    taken by a robot not heard yet, and ``stalled`` ones by a robot not heard for `SILENCE`
    steps while this one stood still (it never moves: a wall to go round, not a robot to wait
    for; waiting for it, the robots beside a stalled one stood still for good). Also, from
    everything it senses: ``mover_near`` (a moving robot heard) and ``outranked`` (a waiting
    robot heard that goes first)."""

    def __init__(
        self, near: _Near, sense: Perception, memory: Memory, moved: np.ndarray, rows: np.ndarray
    ) -> None:
        n, a = len(sense), len(rows)
        index = np.full(n, -1, dtype=np.int64)
        index[rows] = np.arange(a)
        # from everything sensed (up to the sensing radius)
        pick = np.flatnonzero(index[sense.owner] >= 0)
        me = index[sense.owner[pick]]
        seed = sense.seed[pick]
        said = MESSAGE.read(sense.message)
        state = said.state[pick] - 1
        spoke = sense.heard[pick] & sense.kin[pick] & ~seed & (state >= 0)
        stays = (state <= WAIT) | (state >= JOINED)
        self.mover_near = np.zeros(a, dtype=bool)
        self.mover_near[me[spoke & ~stays]] = True
        gradient = np.minimum(said.gradient[pick], INFINITE)
        mine = memory.gradient[rows][me]
        ahead = spoke & (state <= WAIT) & (gradient >= mine)
        ahead &= (gradient > mine) | (said.number[pick] > sense.number[rows][me])
        self.outranked = np.zeros(a, dtype=bool)
        self.outranked[me[ahead]] = True
        # the nearest seed or gradient-holding stationary robot heard (entries run nearest first)
        beacon = (seed & sense.kin[pick] & sense.heard[pick]) | (
            spoke & stays & (gradient < INFINITE)
        )
        first = np.flatnonzero(beacon)
        owners, at = np.unique(me[first], return_index=True)
        toward = np.rint(np.take(sense.offset, pick[first[at]], axis=0)).astype(np.int64)
        self.beacon = np.zeros((a, 2), dtype=np.int64)
        self.beacon[owners] = toward

        # the 5x5 window
        keep = np.flatnonzero(index[near.me] >= 0)
        me = index[near.me[keep]]
        cx, cy, fx, fy = near.cx[keep], near.cy[keep], near.fx[keep], near.fy[keep]
        base, slot = me * 25, near.slot[keep]
        taken = np.zeros(a * 25, dtype=bool)
        taken[base + slot] = True
        # a robot between two cells holds both
        sx = np.where(np.abs(fx) > 0.25, np.sign(fx).astype(np.int64), 0)
        sy = np.where(np.abs(fy) > 0.25, np.sign(fy).astype(np.int64), 0)
        other = (np.abs(cx + sx) <= 2) & (np.abs(cy + sy) <= 2) & ((sx != 0) | (sy != 0))
        taken[(base + slot + sy * 5 + sx)[other]] = True
        self.taken = taken.reshape(a, 25)
        self.taken[:, SELF] = False

        spoke, stays, state = near.spoke[keep], near.stays[keep], near.state[keep]
        centred, seed = near.centred[keep], near.seed[keep] & near.centred[keep]
        still = spoke & stays & centred
        code = np.where(seed, 1, 2 * near.gradient[keep] + (state == JOINED))
        fresh = np.full(a * 25, -1, dtype=np.int64)
        put = still | seed
        fresh[(base + slot)[put]] = code[put]
        mover = np.zeros(a * 25, dtype=bool)
        mover[(base + slot)[spoke & ~stays]] = True
        self.mover = mover.reshape(a, 25)
        following = (state == OUTSIDE) | (state == INSIDE)
        rival = np.zeros(a * 25, dtype=bool)
        free_at_rest = spoke & following & centred & near.unblocked[keep]
        rival[(base + slot)[free_at_rest & near.first[keep]]] = True
        self.rival = rival.reshape(a, 25)
        fresh = fresh.reshape(a, 25)
        # in place, and rows gathered by `np.take`: at 10,000 robots these few lines were a
        # fifth of the program's step, each a pass over a copy of every busy robot's window
        recentred = (moved | near.coming)[rows]  # its window is round another cell now
        known = np.take(memory.known, rows, axis=0)
        known[recentred] = -1
        np.copyto(known, -1, where=~self.taken | self.mover)
        np.copyto(known, fresh, where=fresh >= 0)
        memory.known[rows] = known
        still_there = known >= 0
        self.gradient = np.where(still_there, known >> 1, INFINITE)
        # a joined robot never moves again, so it is a wall with or without a gradient: one
        # that joined beside stalled robots, which pass no gradient on, had none, and the
        # followers that took it for a robot about to move waited behind it for good
        self.joined = still_there & ((known & 1) == 1)
        self.stationary = still_there & (self.gradient < INFINITE) | self.joined
        foreign = np.zeros(a * 25, dtype=bool)
        foreign[(base + slot)[~near.kin[keep]]] = True
        self.foreign = foreign.reshape(a, 25)
        unknown = self.taken & ~still_there & ~self.mover & ~self.foreign
        unheard = np.take(memory.unheard, rows, axis=0)
        unheard[recentred] = 0
        unheard += 1
        unheard *= unknown
        memory.unheard[rows] = unheard
        self.stalled = unheard >= SILENCE
        self.unknown = unknown & ~self.stalled
        facing = np.zeros(a * 25, dtype=bool)
        facing[(base + slot)[near.facing[keep]]] = True
        self.facing = facing.reshape(a, 25)
        self.ready = sense.ready[rows]
        self.coming = near.coming[rows]


def _odometry(sense: Perception, memory: Memory, moved: np.ndarray) -> None:
    """Dead reckoning: a localised robot adds the cells it moved; its heading is its last move."""
    memory.position[memory.localised] += sense.moved[memory.localised]
    for direction in range(1, 5):
        went = (sense.moved == STEPS[direction]).all(axis=1)
        memory.heading[went] = direction
    memory.travelled[moved] += 1


def _gradient(view: _View, memory: Memory) -> None:
    """Stationary robots keep the least value their touching stationary neighbours give (the
    paper's gradient distance of 1.5 bodies: the 8 cells around); values only fall, since a
    robot leaves only when no neighbour's value depends on it."""
    least = view.gradient[:, NEAR8].min(axis=1)
    offer = np.where(least >= INFINITE, INFINITE, least + 1)
    still = np.isin(memory.state, STATIONARY)
    memory.gradient = np.where(still, np.minimum(memory.gradient, offer), offer)


def _localise(sense: Perception, memory: Memory) -> None:
    """Robots at rest near seeds or joined robots fix their position from them: the mean of
    each reference's position less its sensed offset (two are needed for a first fix), and
    move a quarter of the way there (the paper's step); joined and stopped robots keep
    theirs: a stopped one that went on fixing it from noisy offsets changed its broadcast
    every step, so a run whose last robots had stopped never came to rest (`QUIET`)."""
    n = len(sense)
    said = MESSAGE.read(sense.message)
    robot = sense.heard & sense.kin & ~sense.seed & (said.state == JOINED + 1)
    robot &= said.localised == 1
    seed = sense.heard & sense.kin & sense.seed
    open_ = (memory.state != JOINED) & (memory.state != STOPPED)
    open_owner = sense.ready & open_
    use = np.flatnonzero((robot | seed) & open_owner[sense.owner])
    me = sense.owner[use]
    reference = np.where(
        seed[use, None], sense.seed_frame[use].astype(np.float64), said.position[use] / FIXED
    )
    estimate = reference - sense.offset[use]
    count = np.bincount(me, minlength=n)
    total = np.column_stack(
        [np.bincount(me, estimate[:, 0], minlength=n), np.bincount(me, estimate[:, 1], n)]
    )
    fix = total / np.maximum(count, 1)[:, None]
    first = open_ & ~memory.localised & (count >= 2)
    memory.position[first] = fix[first]
    again = open_ & memory.localised & (count >= 1)
    memory.position[again] += (fix[again] - memory.position[again]) / 4
    memory.localised |= first


def _frame_cell(memory: Memory) -> np.ndarray:
    return np.rint(memory.position).astype(np.int64)


def _leave(view: _View, memory: Memory, options: SelfAssembly.Options) -> None:
    """Waiting robots with a gradient leave one at a time; those without one for
    ``options.alone`` steps, or with no neighbour at all, walk off to find the structure."""
    state = memory.state
    waiting = state == WAIT
    if not waiting.any():  # once the robots have left or wandered off, most steps
        memory.eligible = np.zeros_like(memory.eligible)
        return
    first = waiting & (memory.gradient < INFINITE) & ~view.outranked & ~view.mover_near
    heading = _first_heading(view, first)
    first &= heading > 0
    memory.eligible = np.where(first, memory.eligible + 1, 0)
    lossy = memory.since_loss < options.loss_memory
    patience = np.where(lossy, options.lossy_patience, options.patience)
    go = first & (memory.eligible >= patience) & view.ready
    state[go] = OUTSIDE
    memory.heading[go] = heading[go]
    memory.travelled[go] = 0
    lonely = waiting & (memory.gradient >= INFINITE)
    lonely &= (memory.age > options.alone) | ~view.taken[:, NEAR8].any(axis=1)
    state[lonely] = WANDER


def _first_heading(view: _View, robots: np.ndarray) -> np.ndarray:
    """For the `robots` (a mask), the heading that puts the stationary robots on the right: a
    free direction whose right side is stationary, or else one whose front-right cell is; 0
    if none, and for every other robot."""
    heading = np.zeros(len(view.ready), dtype=np.int64)
    rows = np.flatnonzero(robots)
    taken, stationary = view.taken[rows], view.stationary[rows]
    chosen = np.zeros(len(rows), dtype=np.int64)
    for wall in (RIGHT_SIDE, FRONT_RIGHT):
        for d in (1, 3, 2, 4):
            fits = (chosen == 0) & ~taken[:, AHEAD[d]] & stationary[:, wall[d]]
            chosen[fits] = d
    heading[rows] = chosen
    return heading


def _follow(view: _View, sense: _Where, memory: Memory, moves: np.ndarray) -> None:
    """Edge-followers at rest take their next wall-follower step, or join. One under way
    (`_View.coming`) works out, from the cell it is coming to, what it would do there at rest
    (its window is round that cell, `_Near`), and goes on without braking when that is
    straight on; anything else it does once there, at rest. Stopping on every cell, a
    follower took about five steps a cell at the default limits against two at top speed."""
    n = len(sense)
    state = memory.state
    rows = np.arange(n)
    going = np.isin(state, (OUTSIDE, INSIDE)) & (view.ready | view.coming)
    going &= ~view.unknown[:, NEAR8].any(axis=1)
    if not going.any():  # while the robots wander or wait, most steps
        memory.want = np.zeros_like(memory.want)
        memory.held = np.zeros_like(memory.held)
        return
    resting = going & view.ready
    cell = _frame_cell(memory) + view.coming[:, None] * np.take(STEPS, sense.heading, axis=0)
    in_shape = memory.localised & sense.blueprint.contains(sense.group, cell)
    state[resting & (state == OUTSIDE) & in_shape] = INSIDE
    choice = np.zeros(n, dtype=np.int64)
    way = np.zeros(n, dtype=np.int64)  # the same, passing by a follower that faces this one
    # one that started boxed in (`_arrive`) has no heading yet: it sets off with the
    # structure on its right as soon as a cell lets it (east while none does)
    heading = np.where(
        memory.heading > 0, memory.heading, _first_heading(view, going & (memory.heading == 0))
    )
    heading[heading == 0] = 1
    heading[view.coming] = sense.heading[view.coming]
    walls = view.stationary | view.stalled
    # one going round the wrong way, the structure on its left and none on its right (it
    # stepped back to let a follower pass), turns round: followers going opposite ways met
    # head on along one wall, where neither could step aside, and waited for good
    right = walls[rows[:, None], HANDS["right"][heading]].any(axis=1)
    left = walls[rows[:, None], HANDS["left"][heading]].any(axis=1)
    heading = np.where(going & left & ~right, REVERSE[heading], heading)
    for turn in (RIGHT, np.arange(5), LEFT, REVERSE):
        d = turn[heading]
        target = AHEAD[d]
        wall = walls[rows, target]
        contact = walls[rows[:, None], AROUND[d]].any(axis=1)
        fits = (choice == 0) & ~wall & contact
        choice[fits] = d[fits]
        fits = (way == 0) & ~wall & ~view.facing[rows, target] & ~view.foreign[rows, target]
        fits &= contact
        way[fits] = d[fits]
    # boxed in but for a follower facing it (the only way on is back, where the follower
    # behind it waits to come): it asks for that cell, so the one facing it steps aside. Asking
    # for none, it stood, and the one behind waited for it for good (a dead end outside the
    # shape, walled by a stalled robot, fuzz case 44)
    way = np.where(way == 0, choice, way)
    inside = going & ((state == INSIDE) | (view.coming & in_shape))
    four = NEAR8[[1, 3, 4, 6]]
    least = view.gradient[:, NEAR8].min(axis=1)
    mine = np.where(least >= INFINITE, INFINITE, least + 1)
    layer_end = (view.joined[:, four] & (view.gradient[:, four] >= mine[:, None])).any(axis=1)
    layer_end &= mine < INFINITE
    # the next move is the way it would go: stepping past a follower that faces it, an inside
    # robot may turn from the wall, and out of the shape
    leaves = (choice == 0) | ~sense.blueprint.contains(sense.group, cell + STEPS[choice])
    leaves |= ~sense.blueprint.contains(sense.group, cell + STEPS[way])
    # a dead end: walls ahead and on both hands, the only way on back the way it came. The
    # paper's round robots on a continuous floor never meet one inside the shape; on the
    # lattice a stalled robot or a one-cell notch makes one, and the follower turning back met
    # the one behind it head on, each waiting for the other for good. It stops there: its one
    # free side is the cell it came from, so it walls nothing off
    dead_end = choice == REVERSE[heading]
    ends = layer_end | leaves | dead_end
    # never seal a pocket of the shape: step into it instead (see `_pockets`)
    stopping = np.flatnonzero(inside & ends)
    sealed = np.zeros(len(choice), dtype=np.int64)
    pockets = _pockets(walls[stopping])
    for d in range(1, 5):
        beside = cell[stopping] + STEPS[d]
        pocket = pockets[:, d - 1] & sense.blueprint.contains(sense.group[stopping], beside)
        sealed[stopping[(sealed[stopping] == 0) & pocket]] = d
    # nor stop where the free cells beside it may part (see `_onward`): on into the shape
    onward = np.zeros(len(choice), dtype=np.int64)
    on = stopping[sealed[stopping] == 0]
    barred = view.facing[on] | view.foreign[on]
    onward[on] = _onward(walls[on], barred, way[on], cell[on], sense.group[on], sense.blueprint)
    join = inside & ends & (sealed == 0) & (onward == 0)
    # two followers that stopped in the same step beside the same free cell each took the
    # other for a robot passing by, and walled it in together (the K turned a quarter in a
    # scenario, seed 3: 130 of 131 cells for good). One whose stop would wall it in if a
    # rival (`_View.rival`) stopped too waits while the rival stands there, so the rival goes
    # first; for `SILENCE` steps at most, as for a robot unheard (a rival that long at rest
    # with its way free is not about to stop)
    rivalled = np.zeros(len(choice), dtype=bool)
    rivalled[stopping] = (_pockets((walls | view.rival)[stopping]) & ~pockets).any(axis=1)
    hold = join & resting & rivalled & (memory.held < SILENCE)
    memory.held = np.where(hold, memory.held + 1, 0)
    join &= ~hold
    way = np.where(sealed > 0, sealed, np.where(onward > 0, onward, way))
    way[hold] = 0
    blocked = view.taken[rows, AHEAD[way]]
    cells = np.array([len(c) for c in sense.blueprint.cells], dtype=np.int64)[sense.group]
    lost = ~join & ~hold & (memory.travelled > 32 * np.sqrt(cells) + 100)
    # one under way goes on only straight on, and joins or stops once on the cell, at rest
    cruise = going & view.coming & ~join & ~lost & (way == sense.heading)
    join &= resting
    lost &= resting
    state[join] = JOINED
    memory.gradient[join] = mine[join]
    step = (resting | cruise) & ~join & (way > 0) & ~blocked
    moves[step] = way[step]
    memory.want = np.where(resting & ~join & (way > 0) & blocked, way, 0)
    state[lost] = STOPPED
    moves[lost] = 0


def _arrive(view: _View, memory: Memory, moves: np.ndarray) -> None:
    """Wanderers at rest beside the structure start round it, with it on their right. One
    with no cell free beside it (the structure grew round it, with robots in the last gaps)
    starts too: on a cell of the shape it then joins where it stands (`_follow`); left a
    wanderer, it stood in the followers' way for good (scattered starts put robots on the
    shape's cells)."""
    state = memory.state
    found = (state == WANDER) & view.ready & ~view.unknown[:, NEAR8].any(axis=1)
    found &= (view.stationary[:, NEAR8] & (view.gradient[:, NEAR8] < INFINITE)).any(axis=1)
    heading = _first_heading(view, found)
    found &= (heading > 0) | view.taken[:, AHEAD[1:]].all(axis=1)
    state[found] = OUTSIDE
    memory.heading[found] = heading[found]
    memory.travelled[found] = 0
    moves[found] = heading[found]


def _reach_beside(walls: np.ndarray) -> np.ndarray:
    """Per robot and direction d (1 to 4), the slots of its 5x5 window (`walls`, ``(a, 25)``)
    it could reach from the free cell beside it in direction d without passing its own cell
    or a wall ``(a, 4, 25)``; none where that cell is walled."""
    a = len(walls)
    free = ~walls.reshape(a, 5, 5)
    free[:, 2, 2] = False
    reach = np.zeros((a, 4, 25), dtype=bool)
    if not a:  # most steps: no robot to check
        return reach
    for d in range(1, 5):
        start = np.zeros((a, 5, 5), dtype=bool)
        start[:, 2 + STEPS[d, 1], 2 + STEPS[d, 0]] = True
        reach[:, d - 1] = (distances(~free, start & free) >= 0).reshape(a, 25)
    return reach


def _pockets(walls: np.ndarray) -> np.ndarray:
    """Per robot and direction d (1 to 4, ``(a, 4)``), whether the free cells one step in
    direction d form a pocket that the built structure, stalled robots and the robot itself
    wall in, within its 5x5 window (`walls`, ``(a, 25)``): if the robot stopped here, no robot
    could ever reach them (a lattice's dead ends, which the paper's round robots on a
    continuous floor do not meet). A stalled robot's own cell is no pocket: a follower that
    took it for one waited to step into it for good."""
    reach = _reach_beside(walls)
    return reach.any(axis=2) & ~(reach & BORDER).any(axis=2)


def _onward(
    walls: np.ndarray,
    barred: np.ndarray,
    way: np.ndarray,
    cell: np.ndarray,
    group: np.ndarray,
    blueprint: Blueprint,
) -> np.ndarray:
    """For robots about to stop inside the shape where free cells beside one, in parts that
    run on out of its 5x5 window (`walls`: the structure and stalled robots, ``(a, 25)``),
    lie apart round its own cell: the way on into the shape instead (its `way` if that stays
    in the shape, else the first cell of the shape beside it that is neither walled nor
    `barred`, a follower facing it or another group's robot); 0 for the others. Stopped
    there, it might part free cells of the shape from the robots that would fill them:
    `_pockets` sees a pocket only whole within the window, and robots arriving round the
    structure from everywhere at once closed longer ones. (A part whole within the window is
    a pocket, or a dead end outside the shape that nobody needs.)"""
    a = len(walls)
    if not a:  # most steps: nobody about to stop
        return np.zeros(0, dtype=np.int64)
    beside = ~walls[:, AHEAD[1:]]
    reach = _reach_beside(walls)
    running_on = beside & (reach & BORDER).any(axis=2)
    first = reach[np.arange(a), np.argmax(running_on, axis=1)][:, AHEAD[1:]]
    parts = (running_on & ~first).any(axis=1)
    into = beside & ~barred[:, AHEAD[1:]]
    into &= np.stack([blueprint.contains(group, cell + STEPS[d]) for d in range(1, 5)], axis=1)
    keeps = (way > 0) & into[np.arange(a), np.maximum(way, 1) - 1]
    on = np.where(keeps, way, np.where(into.any(axis=1), np.argmax(into, axis=1) + 1, 0))
    return np.where(parts, on, 0)


def _home_in(view: _View, memory: Memory, moves: np.ndarray, rng: np.random.Generator) -> None:
    """Wanderers at rest that hear the structure step toward it, at random but mostly along
    each axis it is off by."""
    walking = (memory.state == WANDER) & view.ready & (moves == 0)
    noise = rng.random((len(moves), 5))
    noise[:, 0] = 0.0
    bx, by = view.beacon[:, 0], view.beacon[:, 1]
    walking &= (bx != 0) | (by != 0)
    noise[:, 1] += 2.0 * (bx > 0) + (np.abs(bx) >= np.abs(by)) * (bx > 0)
    noise[:, 2] += 2.0 * (bx < 0) + (np.abs(bx) >= np.abs(by)) * (bx < 0)
    noise[:, 3] += 2.0 * (by > 0) + (np.abs(by) > np.abs(bx)) * (by > 0)
    noise[:, 4] += 2.0 * (by < 0) + (np.abs(by) > np.abs(bx)) * (by < 0)
    for d in range(1, 5):
        noise[view.taken[:, AHEAD[d]], d] = -1.0
    choice = noise.argmax(axis=1)
    walking &= noise.max(axis=1) > 0.5
    moves[walking] = choice[walking]


def _roam(
    sense: Perception,
    memory: Memory,
    view: _View,
    rows: np.ndarray,
    moves: np.ndarray,
    turn_every: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of the wanderers of `rows` (with `moves` so far) that hear nothing of the
    structure: `localise.roam`, straight on at speed. They used to step at random, and a
    random walk needs the arena's area squared to find the structure: robots scattered over
    the arena spent most of a run searching."""
    lost = np.zeros(len(sense), dtype=bool)
    lost[rows] = (memory.state[rows] == WANDER) & ~view.beacon.any(axis=1) & (moves == 0)
    index = np.zeros(len(sense), dtype=np.int64)
    index[rows] = np.arange(len(rows))

    def taken(robots: np.ndarray, cells: np.ndarray) -> np.ndarray:
        # the window is measured from where the robot is now: past half a cell under way, the
        # cell two ahead of its own is one further on (a claim refused at worst, never an
        # overlap; looking it up from where it is changed the runs, left for now)
        return view.taken[index[robots], _slot(cells)]

    return roam(sense, memory.roam, lost, taken, turn_every, rng)

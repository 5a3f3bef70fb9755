"""`local-swap`: local task swapping (Wang and Rubenstein, "Shape formation in homogeneous swarms
using local task swapping", IEEE Transactions on Robotics 36(3), 2020).

No global matching and no global queue: robot number k of a group starts with the shape's k-th
cell as its goal (robots numbered past the shape's size are spare), works out where it is from
the seeds and localised neighbours, and walks greedily toward its goal. Neighbours within
range trade goals whenever that shortens their summed squared distance, or when one is blocked
by the other (the trade then sends both on). A trade needs both sides: each robot
broadcasts the neighbour it wants to trade with, and two robots that want each other trade in
the same step, from the same two messages, so a goal is never lost or held twice.
"""

from __future__ import annotations

import functools
from typing import Any, ClassVar

import numpy as np
import scipy

from swarmshape.core.compiled import njit
from swarmshape.core.local import Memory, Program, Slot
from swarmshape.core.motion import DIRECTION_OF, LEFT, REVERSE, RIGHT, STEPS
from swarmshape.core.perception import Blueprint, Boxes, Perception
from swarmshape.core.shape import SEED_CELLS
from swarmshape.strategies import register, routes
from swarmshape.strategies.skills.relay import best_per_robot
from swarmshape.strategies.skills.view import SILENCE

(
    LOCALISED, X, Y, HAS, GX, GY, WANTS, NUMBER, STAYS, HOPS, OX, OY, OPEN_HOPS, TWICE, TX, TY,
    SX, SY, SEEKER_HOPS, LEAVING, KEPT, OPEN_AGE, SPARE_HOPS, SPARE_AGE, MOVING, UNSURE,
) = range(26)  # fmt: skip
"""What a robot broadcasts, in order. STAYS: it was at rest and asked for no move, so next step
it is still on the cell (X, Y) it names, and a neighbour may take its bearings from it. HAS, GX,
GY: whether it holds a goal, and that goal's frame cell. HOPS: hops to the nearest localised
robot (0 if localised), a gradient the lost ones climb down. OX, OY, OPEN_HOPS: a shape cell
that nobody sits on or holds, and hops to the robot that sees it (see `_relay_open`). TWICE,
TX, TY: a goal it hears held twice, by a robot at rest on it and one still on its way (see
`_held_twice`). SX, SY, SEEKER_HOPS: a robot without a goal that calls open cells to it, and
hops to it (see `_relay_seekers`). LEAVING: it pushes its way out of a pocket of the shape
(see `_leaving`). KEPT: it rests on a cell a reshape kept (see `_reshaped`). OPEN_AGE: steps
since the open cell (OX, OY) was last seen open. SPARE_HOPS, SPARE_AGE: hops to a robot without
a goal, and steps since it had none (see `_relay_spares`). MOVING: it was under way, between
two cells (see `_leaving_ahead`). UNSURE: its goal may be held twice (see `_unsure`).
Ages, not steps of a clock: robots
need not agree on the time, and the numbers stay small."""

FAR = 1000
"""HOPS of a robot that hears of no localised robot at all, and OPEN_HOPS of one that knows
of no open cell."""

OPEN_REACH = 64
"""Hops an open cell is relayed, and steps a robot goes on toward one it heard of. At 24
hops, about 70 cells, the last open cells of a 10,000-robot letter S went unheard by twenty
robots without a goal waiting 150 cells away on its other side."""

CALL_REACH = 24
"""Hops a robot's call for open cells is relayed (see `_relay_seekers`): open cells travel
through a formed shape a cell in about ten steps, so only nearby ones are worth calling."""

LOYALTY = 2
"""Hops of news a robot gives up to keep to the open cell it heard of last step. Two seekers
in a horseshoe's bay, with open cells at the ends of both arms, heard of the other one every
few steps, turned each time, and never reached either."""

CLIMB = 8
"""Hops a robot's count to a localised robot may rise within twice as many steps before it
counts as hearing of none (see `_hops`). Robots that lost their bearings far from the others
hear each other tell of a way back that runs through themselves, and count up a hop a step:
three such robots counted to a thousand hops, for a thousand steps, before they set out.
A fixed cap of 24 hops instead left robots at the edge of a 10,000-robot arena, 60 hops
from the localised ones, searching at random; the count of a robot that drifts away from
the others rises a hop in tens of steps."""

PATIENCE = 4
"""Steps a robot waits behind something before it goes round it (see `_go_round`)."""

PUSH_HOPS = 0
"""A robot without a goal trades its way into the shape through a robot resting in its way,
toward an open cell it has news of, only if that robot is this many hops from an open cell
or fewer (0: it sees one itself), and nearer it (each push brings the robot without a goal
nearer, so pushes never go round in a circle). So it never trades toward news that may be
stale, and a formed shape stays as it is: at 1 hop, a spare pushed its way in for a cell
filled two steps before, the last open cell of the shape. Without this a robot in a
horseshoe's bay never reached an open cell just beyond the bay's floor."""

STUCK = 20
"""Steps without getting nearer its target after which a robot takes a random step now and
then (the planner sees three cells round it, and in a shape's bays its choices can go round
a loop of four cells for ever), and a robot without a goal that the shape walls off from
its open cell, or sends the long way round, calls open cells to it (`_cut_off`) and may push
(see `PUSH_HOPS`). A push moves a robot that rests on its goal; walking round costs nobody
else a step, and robots on cells that a reshape keeps stay where they are (see
`_reshaped`). (A robot that had merely been stuck pushed: a spare jammed beside the
new rows of a reshaped square pushed a robot off a kept cell.) A robot pushed out of its
cell pushes on at once: waiting, it was pushed back when `TABU` ran
out, and the two did that for ever at a star's notch."""

SEARCH_AFTER = 100
"""Steps a robot without a goal beside the shape, knowing of no open cell, waits for news
before it walks to random cells of the shape to look for one (see `_search_target`), or,
walled in a pocket the shape encloses, before it pushes its way out (see `_leaving`). Sent at
once, seekers that news would soon have reached walked away from it: the 1,018-robot S took
29 % more steps."""

LAPS = 5
"""Times `STUCK` a robot on its way round the shape (`routes`) may make no headway before it
too takes random steps now and then: two robots passing each other the opposite ways round,
between the shape's margin and the arena's edge, stepped round each other in the same loop of
four cells for 17,000 steps, each time the same way as the other."""

TABU = 10
"""Steps two robots that traded do not trade with each other again: a robot pushed out of
its cell (see `PUSH_HOPS`) stands on it until it can move on, and would otherwise take it
straight back from the one that pushed it, by the distance rule."""

NO_BITMAP = -1
"""A robot's record of its shape's digest before its first step (see `_reshaped`)."""

BIG = 1 << 40
"""Farther than any cell."""

ROUNDABOUT = 2
"""How many times the straight way a stuck robot's way round the shape to an open cell must be
before it calls open cells to it (see `_cut_off`)."""


@register
class LocalSwap(Program):
    name = "local-swap"
    description = "goals by robot number, traded between neighbours (Wang & Rubenstein 2020)"
    message_size = 26
    memory: ClassVar[dict[str, Slot]] = {
        "localised": Slot(bool, False),
        "frame": Slot(np.int64, 0, 2),
        "started": Slot(bool, False),
        "has_goal": Slot(bool, False),
        "goal": Slot(np.int64, 0, 2),
        "wants": Slot(np.int64, -1),
        "waited": Slot(np.int64, 0),
        "blocked_way": Slot(np.int64, 0),
        "detour": Slot(np.int64, 0),
        "at_goal": Slot(bool, False),
        "asked": Slot(np.int64, 0),
        "unaware": Slot(np.int64, 0),
        "roam": Slot(np.int64, 0),
        "crossing": Slot(np.int64, 0, added=True),
        "sweep": Slot(np.int64, 0, added=True),
        "shift": Slot(np.int64, 0, added=True),
        "came": Slot(np.int64, 0),
        "partner": Slot(np.int64, -1),
        "since_trade": Slot(np.int64, 0),
        "gave": Slot(bool, False),
        "given": Slot(np.int64, 0, 2),
        "aim": Slot(np.int64, 0, 2),
        "aim_before": Slot(np.int64, 0, 2, added=True),
        "bitmap": Slot(np.int64, NO_BITMAP, added=True),
        "kept": Slot(bool, False, added=True),
        "closest": Slot(np.int64, 0),
        "stuck": Slot(np.int64, 0),
        "heard": Slot(np.int64, 0, 2),
        "heard_hops": Slot(np.int64, FAR),
        "heard_at": Slot(np.int64, 0, added=True),
        "spare_hops": Slot(np.int64, FAR, added=True),
        "spare_at": Slot(np.int64, 0, added=True),
        "spare_until": Slot(np.int64, -1, added=True),
        "routed": Slot(bool, False),
        "silence": Slot(np.int64, 0),
        "calling": Slot(bool, False),
        "low_hops": Slot(np.int64, FAR),
        "low_age": Slot(np.int64, 0),
        "pocketed": Slot(np.int64, 0),
        "leaving": Slot(bool, False),
        "unheard": Slot(np.int64, 0, added=True),
        "roamed": Slot(bool, False, added=True),
        "unsure": Slot(np.int64, 0, added=True),
    }

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        lost = ~memory.localised
        localise(sense, memory)
        late = sense.step > _crossing(sense)  # cut off longer than the count takes to cross
        memory.roamed |= lost & memory.localised & late  # see `_unsure`
        _first_goals(sense, memory)
        rested = _goals_at_rest(sense, memory)  # before trading, as the messages tell them
        twice, twice_cell = _held_twice(sense, rested)
        _yield_taken(sense, memory)
        _trade(sense, memory)
        silent = _silent_cells(sense, memory)
        _give_up_to_the_silent(sense, memory, silent)
        _reshaped(sense, memory)
        occupied = _occupied(sense)
        _note_walls(sense, memory, occupied)
        seeking = memory.localised & ~memory.has_goal
        spares = _relay_spares(sense, memory, seeking)
        _unsure(sense, memory, spares)
        sight, open_cell, by_shape = _open_in_sight(sense, memory, sense.radius)
        news, news_hops, current = _relay_open(sense, memory, sense.radius, sight, open_cell)
        target = np.where((seeking & (news_hops < FAR))[:, None], news, memory.frame)
        news_hops_now = np.where(current, news_hops, FAR)  # what it tells, pushes and leaves for
        unaware = seeking & (news_hops >= FAR) & ~open_cell
        memory.unaware = np.where(unaware, memory.unaware + 1, 0)
        searching = by_shape & sense.ready & (memory.unaware > SEARCH_AFTER)
        unaware = np.flatnonzero(unaware & (~by_shape | searching))
        target[unaware] = _search_target(
            sense, memory, unaware, searching[unaware], sense.radius, rng
        )
        memory.calling = seeking & (memory.calling | _cut_off(sense, memory, seeking, target))
        out = _leaving(sense, memory, seeking, news, news_hops_now)
        target[out] = memory.frame[out] + STEPS[_way_out(sense, memory.frame[out], out)]
        here = _same(target, memory.frame)
        resting = memory.has_goal & _same(memory.goal, memory.frame)
        seeker, seeker_hops = _relay_seekers(sense, memory, memory.calling)
        way = _deeper(sense, memory, occupied, seeker, seeker_hops)
        passing = resting & (spares < FAR)  # holes surface only for a spare that may fill them
        deepen = memory.localised & sense.ready & (way > 0) & (passing | seeking & open_cell & here)
        memory.goal[deepen] = memory.frame[deepen] + STEPS[way[deepen]]
        memory.has_goal[deepen] = True
        seeking &= ~deepen
        claim = seeking & open_cell & sense.ready & here
        memory.goal[claim], memory.has_goal[claim] = memory.frame[claim], True
        target[memory.has_goal] = memory.goal[memory.has_goal]
        has_goal = memory.localised & memory.has_goal
        memory.at_goal = has_goal & _same(memory.frame, memory.goal)
        going = (has_goal | seeking) & ~_same(memory.frame, target)
        same_aim = _same(target, memory.aim)
        _note_progress(memory, target)
        waypoint = _route(sense, memory, target, going & sense.ready, same_aim, sense.radius)
        arrived = ~_same(sense.moved, STEPS[0])
        back = -sense.moved[arrived]
        memory.came[arrived] = DIRECTION_OF[back[:, 0] + 1, back[:, 1] + 1]
        staying = ~_leaving_ahead(sense)  # a robot may follow the others in (`_plan`)
        behind = _occupied(sense, staying)
        _note_walls(sense, memory, behind)
        behind[np.arange(len(sense)), memory.came] = True
        delta = waypoint - memory.frame
        preferred, first = _plan(sense, delta, behind, going, sense.radius, staying)
        memory.wants = _choose_partner(
            sense, memory, preferred, target, seeking, news, news_hops_now, rested, silent
        )
        moves = _go_round(memory, delta, preferred, first, occupied, going & sense.ready, rng)
        lapped = memory.stuck > LAPS * STUCK  # round a loop on its route too
        astray = going & sense.ready & (memory.stuck > STUCK) & (~memory.routed | lapped)
        astray &= rng.random(len(sense)) < 0.25
        moves[astray] = _random_free(occupied[astray], rng)
        moves[memory.wants >= 0] = 0  # hold still while a trade is agreed
        hops, toward = _hops(sense, memory)
        lost = ~memory.localised
        moves[lost] = 0  # it waits where it is for the bearings to reach it (`_guides`)
        led = lost & (toward > 0)
        memory.roam[led] = toward[led]
        memory.crossing[led | ~lost] = 0  # once it roams again, it sets out afresh
        roaming = lost & _unheard_too_long(sense, memory, hops)
        memory.shift -= roaming & (memory.roam == memory.sweep) & arrived  # a cell of its shift
        moves[roaming] = _roam(sense, memory, occupied, roaming, rng)
        # under way: on toward the cell it plans toward while the cell after the next is
        # nearer it (a detour and a way round the shape turn at cells planned at rest), or
        # on the way it searches for robots with bearings
        onward = np.where((delta * STEPS[sense.heading]).sum(axis=1) >= 2, sense.heading, 0)
        onward[~going | memory.routed | (memory.detour > 0)] = 0
        onward[lost] = np.where(roaming, memory.roam, 0)[lost]
        shifting = roaming & (memory.roam == memory.sweep) & (memory.shift <= 1)
        onward[shifting] = 0  # it brakes on the shift's last cell, to cross from there (`_roam`)
        guide = memory.localised & _guides(sense)
        onward[guide] = 0  # it brakes to a stop on its next cell (`_guides`)
        moves = np.where(sense.ready, moves, _cruise(sense, onward))
        moves[guide & sense.ready] = 0
        memory.asked = moves
        stays = sense.ready & (moves == 0)
        messages = np.column_stack(
            [
                memory.localised,
                memory.frame,
                memory.has_goal,
                memory.goal,
                memory.wants,
                sense.number,
                stays,
                hops,
                news,
                news_hops_now,
                twice,
                twice_cell,
                seeker,
                np.minimum(seeker_hops, FAR),
                memory.leaving,
                memory.kept,
                np.minimum(sense.step - memory.heard_at, FAR),
                spares,
                np.minimum(sense.step - memory.spare_at, FAR),
                ~sense.ready,
                memory.unsure > 0,
            ]
        ).astype(np.int64, copy=False)  # int64 already: no second 2 MB array at 10,000
        return moves, messages

    def finished(self, memory: Memory) -> np.ndarray:
        return memory.at_goal

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
        return memory.localised, memory.frame


def _note_progress(memory: Memory, target: np.ndarray) -> None:
    """Count the steps since each robot last came nearer its target. A new target restarts the
    count, unless it is the one the robot had before its present one, which is measured
    against the nearest it came to either: two seekers in a bay, each turning between two
    open cells as the other's news came and went, never counted as stuck and never called the
    open cells to them (the 98-robot S waited for good on seed 23 of 0 to 39). A
    count carried over to a new target made a spare whose count ran up on the last open cell
    of a shape call open cells through it as soon as it was reshaped. A robot with nowhere
    to go keeps its count and its target: a seeker in a letter S's bay
    lost sight of its open cell every few steps, for a step, and so never counted as stuck.
    One on its goal is not stuck, whatever it met on its way there."""
    left = _apart(target, memory.frame)
    aiming = left > 0
    new = aiming & ~_same(target, memory.aim)
    nearer = aiming & (left < memory.closest) | memory.at_goal
    memory.stuck = np.where(nearer, 0, memory.stuck + aiming)
    fresh = new & ~_same(target, memory.aim_before)
    memory.stuck[fresh] = 0
    memory.closest = np.where(fresh | nearer, left, memory.closest)
    memory.aim_before[new] = memory.aim[new]
    memory.aim[aiming] = target[aiming]


def _reshaped(sense: Perception, memory: Memory) -> None:
    """A robot whose shape changed (`Blueprint.digest`) gives up a goal off the new shape and
    restarts its count and its call (`_cut_off`): they were for the old shape's open cells. A
    spare that had called the last open cell of a square went on calling when the square was
    reshaped, and robots on the cells the reshape kept stepped toward it into the new rows.
    One resting on a goal the new shape keeps is `kept` while it rests there, and says so: it
    passes open cells on by depth but not toward a call (`_deeper`), and trades only with a
    robot leaving a pocket (`_choose_partner`), so robots on kept cells stay put while spare
    ones walk to the new cells. A spare beside a reshaped square's seeds, whose way round was
    a little over twice the straight way, called the new row's open cells through the kept
    rows, and then pushed its way through them."""
    bitmap = sense.blueprint.digest(sense.group)
    changed = memory.bitmap != bitmap
    reshaped = changed & (memory.bitmap != NO_BITMAP)
    memory.bitmap = bitmap
    memory.stuck[changed] = 0
    memory.calling[changed] = False
    memory.has_goal &= sense.blueprint.contains(sense.group, memory.goal)
    resting = memory.has_goal & _same(memory.goal, memory.frame)
    memory.kept = resting & (memory.kept | reshaped)


def _guides(sense: Perception) -> np.ndarray:
    """Robots that hear a robot of their group that has not found its bearings: a localised
    one holds still while they do (under way, it stops on its next cell), since a robot takes
    its bearings only from one that says it stays where it is (`localise`). Localised robots
    walking to their goals stayed nowhere, and before 90 % of the 98-robot S had reached their
    goals, 45 % of the steps of those still on their way went to robots without bearings.

    A robot without bearings that hears a hop count to robots with them waits where it is (one
    that hears none roams, `_roam`): bearings spread from the seeds through robots at rest, a
    ring of neighbours a step or two, faster than a robot walks. Following its neighbours
    toward the localised ones instead, the robots walked a third of the run's distance before
    they knew where they were going (24,834 of the 70,407 cells walked in the 1,018-robot S,
    seed 1; now 2,406 of 48,575, and a robot has its bearings at step 36 on average, against
    88), and at the scattered swarm's far edge the robots with bearings walked on to their
    goals faster than the last ones without them followed: one group lost the hop count 150
    steps in, roamed the empty arena, and came upon the formed shape a thousand steps later."""
    lost = sense.heard & sense.kin & ~sense.seed & (sense.message[:, LOCALISED] == 0)
    near = np.zeros(len(sense), dtype=bool)
    near[sense.owner[lost]] = True
    return near


def _cruise(sense: Perception, onward: np.ndarray) -> np.ndarray:
    """Moves of robots under way: straight on while that is the way it would go on (`onward`)
    and nobody is in or near the cell after the next one, else 0, and it brakes to a stop on
    the next cell, where it plans afresh. Stopping on every cell cost about five steps a
    cell, against two at top speed, and a robot that had lost its bearings fell behind the
    robots it followed to the shape, lost sight of them, and searched the arena for hundreds
    of steps."""
    going = sense.cruising & (onward == sense.heading) & (onward > 0)
    rows = np.flatnonzero(going)
    beyond = np.zeros((len(sense), 2))  # the cell after the next, from where it is now
    beyond[rows] = (2 - sense.progress[rows, None]) * STEPS[sense.heading[rows]]
    entries = np.flatnonzero(going[sense.owner])  # the neighbours of those going on
    owner = sense.owner[entries]
    near = _within(sense.offset[entries] - beyond[owner], 1, strict=True)
    free = np.ones(len(sense), dtype=bool)
    free[owner[near]] = False
    moves = np.zeros(len(sense), dtype=np.int64)
    moves[rows[free[rows]]] = sense.heading[rows[free[rows]]]
    return moves


def _route(
    sense: Perception,
    memory: Memory,
    target: np.ndarray,
    ready: np.ndarray,
    same_aim: np.ndarray,
    radius: float,
) -> np.ndarray:
    """The cell each robot plans toward: its target, or for a robot outside the shape that
    made no headway for `STUCK` steps, a cell a few steps along its way round the shape to
    it (`routes`). It keeps to the route while its target stays the same: back on
    the direct way, it walked straight back to where it was stuck. A robot that sees robots
    it does not hear routes round their cells too (`routes.waypoint_round`): a stalled robot
    stands there for good, and the last open cell of a small shape, walled in by the seeds, a
    stalled robot and a robot resting on its goal, waited 2,000 steps for a seeker whose way
    round the bitmap led through the stalled robot, where it turned back and forth."""
    kept = memory.routed & same_aim
    outside = ~sense.blueprint.contains(sense.group, memory.frame)
    rows = np.flatnonzero(ready & outside & (kept | (memory.stuck > STUCK)))
    cells, found = routes.waypoints(
        sense.blueprint, sense.group[rows], memory.frame[rows], target[rows], int(radius)
    )
    routing = np.zeros(len(sense), dtype=bool)
    routing[rows] = True
    unheard = np.flatnonzero(~sense.heard & ~sense.seed)  # none without lost messages or stalls
    unheard = unheard[routing[sense.owner[unheard]]]
    silent = memory.frame[sense.owner[unheard]] + _cells(sense)[unheard]
    for row in np.unique(sense.owner[unheard]).tolist():
        at = rows == row
        cells[at], found[at] = routes.waypoint_round(
            sense.blueprint, int(sense.group[row]), memory.frame[row], target[row],
            int(radius), silent[sense.owner[unheard] == row],
        )  # fmt: skip
    memory.routed = np.where(ready, False, kept)
    memory.routed[rows[found]] = True
    waypoint = target.copy()
    waypoint[rows[found]] = cells[found]
    return waypoint


def _first_goals(sense: Perception, memory: Memory) -> None:
    """On its first step robot number k takes its shape's k-th cell (none past the shape's
    size): the one assignment every robot can draw alone, unique by construction."""
    new = np.flatnonzero(~memory.started)
    take = new[sense.number[new] < sense.blueprint.count(sense.group[new])]
    memory.goal[take] = sense.blueprint.cell(sense.group[take], sense.number[take])
    memory.has_goal[take] = True
    memory.started[new] = True


def _unsure(sense: Perception, memory: Memory, spares: np.ndarray) -> None:
    """Robots whose goal may be held twice: those that found their bearings late (`roamed`:
    later than a hop count takes to cross the swarm, `_crossing`) while they hear of a robot
    without a goal (`spares`), until they see their goal's cell or hold none. Cut off from the
    others, a robot cannot be heard to hold its goal, and a spare standing on that cell claims
    it; traded on from afar, such a goal reached a robot resting in the formed shape, which
    left its cell for one already filled (fuzz cases 241 and 870). No robot resting on its own
    goal takes an unsure robot's goal out of its sight (both ends know it from its message),
    and an unsure robot kept from its goal `STUCK` steps gives it up and looks for an open
    cell. With one robot per cell no robot is ever unsure: there is no spare to claim a goal.

    Over cases 0 to 1,019 of `scripts/fuzz_programs.py local-swap`, the runs with a problem
    fell from 21 to 11, and those whose formed shape lost a cell from 16 to 7. Given up at
    once when kept from its goal, robots counted as stuck from their steps without bearings
    gave up goals they had just found, and a 1,000-cell disc with a quarter more robots took
    60 % longer; as here it takes 318 to 408 steps (seeds 0 to 4), against 369 to 388."""
    in_sight = np.hypot(*(memory.goal - memory.frame).T) <= sense.radius
    memory.roamed &= memory.has_goal & ~in_sight
    unsure = memory.roamed & ((memory.unsure > 0) | (spares < FAR))
    memory.unsure = np.where(unsure, memory.unsure + 1, 0)
    walled = (memory.unsure > STUCK) & (memory.stuck > STUCK)
    memory.has_goal[walled] = memory.roamed[walled] = False
    memory.unsure[walled] = 0


def _yield_taken(sense: Perception, memory: Memory) -> None:
    """Give up a goal that a neighbour holds too and already rests on, or that a neighbour
    says is held so (`_held_twice`). Goals are unique except after a spare robot claimed a
    cell whose holder was out of range; the one that got there keeps it. A goal traded for
    in the last two steps is not the one a neighbour's word is about (it spoke a step before
    the trade)."""
    heard = sense.heard & sense.kin & ~sense.seed
    memory.has_goal[
        _held_by_others(
            sense.owner, heard, sense.message, memory.has_goal, memory.goal, memory.frame,
            memory.since_trade,
        )
    ] = False  # fmt: skip


@njit
def _held_by_others(
    owner: np.ndarray,
    heard: np.ndarray,
    msg: np.ndarray,
    has_goal: np.ndarray,
    goal: np.ndarray,
    frame: np.ndarray,
    since_trade: np.ndarray,
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_yield_taken`, entry by entry: which robots off their goal hear a localised
    neighbour resting on it, or one that says it is held twice. As numpy passes it gathered
    every robot's goal for each of its entries three times, a tenth of the step at 10,000
    robots."""
    drop = np.zeros(len(has_goal), dtype=np.bool_)
    for e in range(len(owner)):
        m = owner[e]
        gx, gy = goal[m, 0], goal[m, 1]
        if not heard[e] or not has_goal[m] or (frame[m, 0] == gx and frame[m, 1] == gy):
            continue
        x, y = msg[e, X], msg[e, Y]
        there = msg[e, LOCALISED] == 1 and msg[e, STAYS] == 1 and msg[e, HAS] == 1
        there = there and x == msg[e, GX] and y == msg[e, GY] and x == gx and y == gy
        told = msg[e, TWICE] == 1 and msg[e, TX] == gx and msg[e, TY] == gy
        drop[m] |= there or (told and since_trade[m] > 1)
    return drop


def _goals_at_rest(sense: Perception, memory: Memory) -> np.ndarray:
    """Sorted keys (`_key`) of each robot and a goal it knows a robot rests on: a neighbour
    that says so, or itself."""
    heard = sense.heard & sense.kin & ~sense.seed
    own = memory.localised & memory.has_goal & _same(memory.frame, memory.goal)
    return np.sort(
        np.concatenate(
            [
                _resting_keys(sense.owner, heard, sense.message),
                _key(np.flatnonzero(own), memory.goal[own]),
            ]
        )
    )


@njit
def _resting_keys(
    owner: np.ndarray, heard: np.ndarray, msg: np.ndarray
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_key` of each robot and the goal of each localised neighbour it hears (`heard`)
    resting on it, entry by entry (as numpy passes, a twentieth of the step at 10,000
    robots)."""
    keys = np.empty(len(owner), dtype=np.int64)
    count = 0
    for e in range(len(owner)):
        x, y = msg[e, X], msg[e, Y]
        still = msg[e, LOCALISED] == 1 and msg[e, STAYS] == 1
        if heard[e] and still and msg[e, HAS] == 1 and x == msg[e, GX] and y == msg[e, GY]:
            keys[count] = _key_of(owner[e], x, y)
            count += 1
    return keys[:count]


def _key(robot: np.ndarray, cell: np.ndarray) -> np.ndarray:
    """One integer per robot and frame cell, for set lookups (`_among`)."""
    return _key_of(robot.astype(np.int64), cell[:, 0], cell[:, 1])


SPAN = 1 << 21
"""Frame cells of a `_key` lie within SPAN // 2 of the seeds on both axes."""


@njit
def _key_of(robot: Any, x: Any, y: Any) -> Any:  # pragma: no cover (compiled)
    """`_key` of robots and cells given as numbers or arrays (a kernel calls it too)."""
    return (robot * SPAN + x + SPAN // 2) * SPAN + y + SPAN // 2


@njit
def _known(key: int, known: np.ndarray) -> bool:  # pragma: no cover (compiled)
    """Whether `key` is in the sorted array `known` (`_among` of one key)."""
    at = np.searchsorted(known, key)
    return at < len(known) and known[at] == key


def _same(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row by row, whether cells ``(k, 2)`` are equal (either side may be one cell).
    ``(a == b).all(axis=1)`` is ten times slower: numpy reduces two columns slowly."""
    return (a[..., 0] == b[..., 0]) & (a[..., 1] == b[..., 1])


def _apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row by row, the taxicab distance between cells ``(k, 2)`` (either side may be one)."""
    return np.abs(a[..., 0] - b[..., 0]) + np.abs(a[..., 1] - b[..., 1])


def _within(a: np.ndarray, reach: float, strict: bool = False) -> np.ndarray:
    """Row by row, whether offsets ``(k, 2)`` lie within `reach` on both axes (below it if
    `strict`)."""
    inside = np.less if strict else np.less_equal
    return inside(np.abs(a[:, 0]), reach) & inside(np.abs(a[:, 1]), reach)


def _among(keys: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Whether each of `keys` is in the sorted array `known`: a binary search of the keys in
    sorted order. At 10,000 robots `np.isin`, with `np.unique` for the sets, took five times
    as long (numpy 2.4's `unique` goes by a hash table, a hundred times slower than its sort
    on these keys)."""
    if len(known) == 0:
        return np.zeros(len(keys), dtype=bool)
    order = np.argsort(keys)
    at = np.minimum(np.searchsorted(known, keys[order]), len(known) - 1)
    found = np.empty(len(keys), dtype=bool)
    found[order] = known[at] == keys[order]
    return found


def _held_twice(sense: Perception, rested: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per robot, whether it hears a neighbour on its way to a goal that another robot rests
    on, and that goal: it says so, and the one on its way gives the goal up. Without this a
    spare robot that claimed a cell whose holder was far away kept the goal, traded it into
    the formed shape, and a robot there left its cell for it."""
    heard = sense.heard & sense.kin & ~sense.seed
    first = _first_held_twice(sense.owner, heard, sense.message, rested, len(sense))
    cell = np.zeros((len(sense), 2), dtype=np.int64)
    cell[first >= 0] = sense.message[first[first >= 0], GX : GY + 1]
    return first >= 0, cell


@njit
def _first_held_twice(
    owner: np.ndarray, heard: np.ndarray, msg: np.ndarray, rested: np.ndarray, n: int
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_held_twice`, entry by entry: per robot (of `n`), its first `heard` entry from a
    localised neighbour on its way to a goal in `rested`, or -1. As numpy passes it looked up
    every entry's goal, a tenth of the step at 10,000 robots."""
    first = np.full(n, -1, dtype=np.int64)
    for e in range(len(owner)):
        m = owner[e]
        if first[m] >= 0 or not heard[e] or msg[e, LOCALISED] != 1 or msg[e, HAS] != 1:
            continue
        gx, gy = msg[e, GX], msg[e, GY]
        if (msg[e, X] != gx or msg[e, Y] != gy) and _known(_key_of(m, gx, gy), rested):
            first[m] = e
    return first


def _open_in_sight(
    sense: Perception, memory: Memory, radius: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per robot, the nearest shape cell within sensing range that no neighbour sits on or
    holds, and whether there is one; and whether it sees any shape cell at all. After a
    reshape or a fault the open cells have no holder, and only robots that look for them can
    fill them. Its own cell counts (a robot standing on an open cell claims it), its own goal
    does not, nor one it has just traded away (its partner's message saying so is a step
    behind; a robot pushed out of its cell claimed it straight back). A robot on the move sees
    none: it senses its neighbours from between two cells, and rounded to cells they showed a
    filled cell open each time it moved; a seeker with 10 % of messages lost turned to that
    cell and back to its news every few steps, never counted as stuck, and so never went
    round the shape to the open cells (a star, seed 3)."""
    recent = memory.gave & (memory.since_trade < TABU)
    disc, reach = _disc(radius), int(radius)
    squares = sense.blueprint.contains_around(sense.group, memory.frame, reach)
    inside = squares[:, disc[:, 0] + reach, disc[:, 1] + reach]
    holds = sense.heard & sense.kin & ~sense.seed & (sense.message[:, HAS] == 1)
    taken = _taken(
        sense.owner, _cells(sense), holds, sense.message, memory.frame, memory.has_goal,
        memory.goal, recent, memory.given, _disc_index(radius),
    )  # fmt: skip
    free = inside & ~taken & (memory.localised & sense.ready)[:, None]
    return memory.frame + disc[free.argmax(axis=1)], free.any(axis=1), inside.any(axis=1)


@njit
def _taken(
    owner: np.ndarray,
    sat: np.ndarray,
    holds: np.ndarray,
    msg: np.ndarray,
    frame: np.ndarray,
    has_goal: np.ndarray,
    goal: np.ndarray,
    recent: np.ndarray,
    given: np.ndarray,
    index: np.ndarray,
) -> np.ndarray:  # pragma: no cover (compiled)
    """``(n, len(_disc))``: which cells of each robot's sensing disc (`index`, see
    `_disc_index`) are taken, for `_open_in_sight`: a neighbour sits on it (`sat`, its
    offset in cells) or holds it (`holds`: a goal it says it has), or the robot holds it or has
    just traded it away (`recent`: it gave `given`). As numpy passes, gathering the goals of
    every entry, it took a sixth of the step at 10,000 robots."""
    reach = index.shape[0] // 2
    taken = np.zeros((len(frame), index.max() + 1), dtype=np.bool_)

    def mark(robot: int, dx: int, dy: int) -> None:
        if abs(dx) <= reach and abs(dy) <= reach and index[dx + reach, dy + reach] >= 0:
            taken[robot, index[dx + reach, dy + reach]] = True

    for e in range(len(owner)):
        m = owner[e]
        mark(m, sat[e, 0], sat[e, 1])
        if holds[e]:
            mark(m, msg[e, GX] - frame[m, 0], msg[e, GY] - frame[m, 1])
    for m in range(len(frame)):
        if has_goal[m]:
            mark(m, goal[m, 0] - frame[m, 0], goal[m, 1] - frame[m, 1])
        if recent[m]:
            mark(m, given[m, 0] - frame[m, 0], given[m, 1] - frame[m, 1])
    return taken


@functools.lru_cache(maxsize=4)
def _disc(radius: float) -> np.ndarray:
    """The cell offsets within `radius`, nearest first (by steps, then straight-line)."""
    reach = int(radius)
    span = np.arange(-reach, reach + 1)
    grid = np.stack(np.meshgrid(span, span, indexing="ij"), axis=-1).reshape(-1, 2)
    grid = grid[np.hypot(*grid.T) <= radius]
    return grid[np.lexsort((np.hypot(*grid.T), np.abs(grid).sum(axis=1)))]


@functools.lru_cache(maxsize=4)
def _disc_index(radius: float) -> np.ndarray:
    """Each offset's place in `_disc` (offsets from ``-reach`` stored from 0), or -1."""
    reach = int(radius)
    index = np.full((2 * reach + 1, 2 * reach + 1), -1, dtype=np.int64)
    disc = _disc(radius)
    index[disc[:, 0] + reach, disc[:, 1] + reach] = np.arange(len(disc))
    return index


def _relay_open(
    sense: Perception,
    memory: Memory,
    radius: float,
    sight: np.ndarray,
    seen: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An open cell each robot knows of, hops to the robot that sees it (FAR: none), and
    whether the news is current (`_current`): its own sight, or the current news with fewest
    hops that its neighbours relay. A robot trusts its own eyes over news of a cell in its
    range. Robots without a goal head for it, so an open cell anywhere, even deep inside the
    shape, draws them in; walking round the shape until one came in sight took hundreds of
    steps on an 8 by 8 square. A robot that hears no news goes on by the last it heard, for up
    to `OPEN_REACH` steps: one in the bay of a 1,000-cell letter S walked toward an open cell,
    out of earshot of the robots that told of it, back to them, and so on for thousands of
    steps. It tells others, pushes (`PUSH_HOPS`) and leaves a pocket (`_leaving`) only for
    current news, and takes no news of the cell it knows from a neighbour with more hops and
    none fresher: counted in hops alone, a filled cell's news went round the robots near it a
    hop more each step, and a robot walled in a pocket of a formed shape pushed its way out
    for it 59 steps after the shape had formed."""
    msg = sense.message
    best = _news_heard(
        sense.owner, sense.heard & sense.kin & ~sense.seed, msg, sense.step, memory.localised,
        memory.frame, memory.heard, memory.heard_at, memory.heard_hops, radius,
    )  # fmt: skip
    told = (best >= 0) & ~seen
    cell, at = sight.copy(), np.full(len(sense), sense.step, dtype=np.int64)
    hops_to = np.where(seen, 0, FAR)
    cell[told], at[told] = msg[best[told], OX : OY + 1], sense.step - 1 - msg[best[told], OPEN_AGE]
    hops_to[told] = msg[best[told], OPEN_HOPS] + 1
    recall = (hops_to >= FAR) & (memory.heard_hops < FAR) & memory.localised
    recall &= sense.step - memory.heard_at < OPEN_REACH
    recall &= np.hypot(*(memory.heard - memory.frame).T) > radius
    cell[recall], hops_to[recall] = memory.heard[recall], memory.heard_hops[recall]
    at[recall] = memory.heard_at[recall]
    memory.heard, memory.heard_hops, memory.heard_at = cell.copy(), hops_to.copy(), at
    return cell, hops_to, (hops_to < FAR) & _current(sense.step - at, hops_to)


@njit
def _news_heard(
    owner: np.ndarray,
    heard: np.ndarray,
    msg: np.ndarray,
    step: int,
    localised: np.ndarray,
    frame: np.ndarray,
    known_cell: np.ndarray,
    known_at: np.ndarray,
    known_hops: np.ndarray,
    radius: float,
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_relay_open`'s choice among the `heard` entries, in reach order: per localised robot,
    the entry with the fewest hops (`LOYALTY` fewer for the cell it knows of, and of equals
    the nearest) that tells current news of an open cell out of its sight, and not the cell it
    knows of with more hops and none fresher; or -1. As numpy passes, gathering each robot's
    frame and news for every entry, it took a tenth of the step at 10,000 robots."""
    best = np.full(len(localised), -1, dtype=np.int64)
    least = np.zeros(len(localised), dtype=np.int64)
    for e in range(len(owner)):
        m = owner[e]
        if not heard[e] or not localised[m] or msg[e, OPEN_HOPS] >= OPEN_REACH:
            continue
        hops, stamp = msg[e, OPEN_HOPS] + 1, step - 1 - msg[e, OPEN_AGE]
        x, y = msg[e, OX], msg[e, OY]
        known = x == known_cell[m, 0] and y == known_cell[m, 1]
        key = hops - LOYALTY * known
        if best[m] >= 0 and key >= least[m]:  # no better: skip the dearer checks (most do)
            continue
        away = np.hypot(float(x - frame[m, 0]), float(y - frame[m, 1]))
        if not _current(step - stamp, hops) or away <= radius:
            continue
        if known and stamp <= known_at[m] and hops > known_hops[m]:
            continue
        best[m], least[m] = e, key
    return best


@njit
def _current(age: Any, hops: Any) -> Any:  # pragma: no cover (compiled)
    """Whether news `age` steps old, from a robot `hops` away (that saw an open cell, or had
    no goal), may still be true: relayed a hop a step it is as old as it is far, and each
    message lost on its way makes it a step older, so it is current while no older than twice
    its hops (as many steps late as hops: one message in two lost, `--msg-loss` 0.5, on
    average). Once nobody renews it, it is current no more within as many steps as it is
    hops away; counted in hops alone it went on for up to `OPEN_REACH` steps."""
    return age <= 2 * hops


def _relay_spares(sense: Perception, memory: Memory, seeking: np.ndarray) -> np.ndarray:
    """Hops to the nearest robot without a goal (`seeking`) that each robot has current news
    of (`_current`; FAR: none): itself (0), or the freshest news its neighbours relay, of
    equals the fewest hops, unless its own is as good, current or not (so once a spare has a
    goal, its news ages where it is and dies, instead of coming back with more hops). Robots
    resting on their goals pass open cells on (`_deeper`) only while they know of one: once
    the last spare had taken a cell of a shape that faults had left short of robots, the
    others went on passing its open cells toward the rim, and the formed shape lost a cell
    with each. A robot takes no news as old as its own last step without a goal: it may be
    its own, echoed back."""
    me, msg = sense.owner, sense.message
    hops, seen = msg[:, SPARE_HOPS] + 1, sense.step - 1 - msg[:, SPARE_AGE]
    told = sense.heard & sense.kin & ~sense.seed & (msg[:, SPARE_HOPS] < OPEN_REACH)
    told &= _current(sense.step - seen, hops) & (seen > memory.spare_until[me])
    key = (sense.step - seen) * (FAR + 1) + hops  # the freshest, then the fewest hops
    best = best_per_robot(len(sense), me, key, told)
    own = (sense.step - memory.spare_at) * (FAR + 1) + memory.spare_hops
    better = np.flatnonzero(best >= 0)
    better = better[key[best[better]] < own[better]]
    memory.spare_hops[better], memory.spare_at[better] = hops[best[better]], seen[best[better]]
    memory.spare_hops[seeking], memory.spare_at[seeking] = 0, sense.step
    memory.spare_until[seeking] = sense.step
    current = _current(sense.step - memory.spare_at, memory.spare_hops)
    return np.where(current & (memory.spare_hops < FAR), memory.spare_hops, FAR)


def _search_target(
    sense: Perception,
    memory: Memory,
    rows: np.ndarray,
    searching: np.ndarray,
    radius: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Where robots without a goal that know of no open cell head: on to the shape cell they
    were heading for while it is out of sight, or else the shape's nearest cell, or for those
    `searching` (beside it, `SEARCH_AFTER` steps without news) a random cell of it. A seeker
    in a letter S's bay, out of sight of both arms, heard of an open cell in one arm only
    while near the other, and walked to and fro between the two for good; one beside the
    10,000-robot S, beyond the reach of any news, stood still for good while the last open
    cell waited. It gives up a cell it has made no headway to for `SEARCH_AFTER` steps: ten
    robots beside a word's first two letters, cut off from the open cells of its last two,
    all kept on to a cell inside a letter whose news had died, for good."""
    target = _nearest_cell(sense, memory, rows)
    groups = sense.group[rows]
    counts = sense.blueprint.count(groups)
    seen = np.flatnonzero(searching & (counts > 0))
    if len(seen):
        pick = rng.integers(0, counts[seen])
        target[seen] = sense.blueprint.cell(groups[seen], pick)
    aim = memory.aim[rows]
    onward = sense.blueprint.contains(groups, aim)
    onward &= np.hypot(*(aim - memory.frame[rows]).T) > radius
    onward &= memory.stuck[rows] <= SEARCH_AFTER  # one it cannot reach it gives up
    target[onward] = aim[onward]
    return target


def _nearest_cell(sense: Perception, memory: Memory, rows: np.ndarray) -> np.ndarray:
    """For robots out of sight of the shape, its nearest cell."""
    target = memory.frame[rows].copy()
    for group, cells in enumerate(sense.blueprint.cells):
        mine = sense.group[rows] == group
        if mine.any() and len(cells):
            far = np.abs(memory.frame[rows[mine], None, :] - cells[None, :, :]).sum(axis=2)
            target[mine] = cells[far.argmin(axis=1)]
    return target


def _cut_off(
    sense: Perception, memory: Memory, seeking: np.ndarray, target: np.ndarray
) -> np.ndarray:
    """Robots without a goal, outside the shape, that stand in a pocket the shape encloses,
    or that are stuck and the shape walls off from the open cell they head for, or whose way
    round to it is more than `ROUNDABOUT` times the straight way (`routes.ways`): they call
    the open cells to them (see `_deeper`) until they have a goal. One that could walk there
    does not, so robots on cells a reshape keeps stay put while spare ones fill the new rows.
    One that called only while stuck stopped each time the open cell came nearer, and the
    robots that did not hear it sent it back: in a ring's hole the open cell went up and down
    the ring's side for good. One in a pocket calls at once: it can leave only through the
    shape, however near the open cell (one a robot's cell away crossed no more of the shape
    than a way in from outside, and was never called), and one whose news flickered between
    three open cells never counted as stuck."""
    outside = seeking & ~_same(target, memory.frame)
    outside &= ~sense.blueprint.contains(sense.group, memory.frame)
    calling = outside & (_depths(sense.blueprint)[1].at(sense.group, memory.frame) > 0)
    rows = np.flatnonzero(outside & ~calling & (memory.stuck > STUCK))
    frame, group = memory.frame[rows], sense.group[rows]
    walked, walled = routes.ways(sense.blueprint, group, frame, target[rows])
    straight = _apart(target[rows], frame)
    calling[rows] = np.isfinite(walked) & ((walled > 0) | (walked > ROUNDABOUT * straight))
    return calling


def _pushed_on(memory: Memory) -> np.ndarray:
    """Robots that traded their goal away and still stand on it: pushed out of their cell, they
    push on at once (see `PUSH_HOPS`)."""
    return memory.gave & (memory.since_trade < TABU) & _same(memory.given, memory.frame)


def _leaving(
    sense: Perception, memory: Memory, seeking: np.ndarray, news: np.ndarray, news_hops: np.ndarray
) -> np.ndarray:
    """Robots without a goal that push their way out of a pocket the shape encloses. One in a
    pocket calls open cells to it (`_cut_off`), but they travel only through the shape and the
    robots it can talk to: the last open cell may lie in another piece of the shape, and a robot
    in the counter of a letter A or o waited for good (a word at 40 and 60 cells, 99.1 to 99.8
    per cent). One that knows of an open cell in the piece round its pocket waits for it to be
    pulled in, and so does one that knows of none: the shape may be formed, and a spare that
    pushed its way out of it would open a cell of the formed shape. After `SEARCH_AFTER` steps
    in a pocket without a goal, told only of open cells in other pieces (steps, not steps
    without headway: the news it heads for changes, and a robot roaming its pocket comes nearer
    now and then), it pushes the robot in its way out (`_way_out`), and each robot
    pushed pushes on the next (see `_trade`), until the last of the chain steps out of the shape
    and looks for the open cell as any robot outside does. Each push moves the want of a goal
    one cell outward and hands a cell to the robot behind, so the chain ends at the shape's rim
    and exactly one robot leaves; robots on their goals and robots outside the shape's pockets
    never start one."""
    depth = _depths(sense.blueprint)[1].at(sense.group, memory.frame)
    pocket = seeking & ~sense.blueprint.contains(sense.group, memory.frame) & (depth > 0)
    rows = np.flatnonzero(pocket)
    pieces, groups = _pieces(sense.blueprint), sense.group[rows]
    round_it = _piece_round(sense, memory.frame[rows], rows)
    told = news_hops[rows] < FAR
    pulled = ~told | (pieces.at(groups, news[rows]) == round_it)
    waiting = np.zeros(len(sense), dtype=bool)
    waiting[rows[~pulled]] = True
    memory.pocketed = np.where(waiting, memory.pocketed + 1, 0)
    walled_in = memory.pocketed > SEARCH_AFTER
    memory.leaving = seeking & (depth > 0) & (memory.leaving | walled_in)
    return memory.leaving


@functools.lru_cache(maxsize=4)
def _pieces(blueprint: Blueprint) -> Boxes:
    """Per group, its shape's pieces numbered from 1 (cells joined side to side, as robots
    step and open cells travel), 0 outside, in the box of `_depths`."""
    out = []
    for (low, grid), shape in zip(_depth(blueprint).boxes, blueprint.cells, strict=True):
        cells = np.zeros(grid.shape, dtype=bool)
        cells[shape[:, 0] - low[0], shape[:, 1] - low[1]] = True
        out.append((low, scipy.ndimage.label(cells)[0]))
    return Boxes(out)


def _piece_round(sense: Perception, frame: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """For robots in pockets at `frame`, the piece of the shape (`_pieces`) their way out
    (`_way_out`) first crosses: the one round the pocket, which open cells can travel in; 0 for
    a pocket walled off by the seeds alone (a cut corner beside them), whose way out crosses no
    piece."""
    pieces, groups = _pieces(sense.blueprint), sense.group[rows]
    enclosed = _depths(sense.blueprint)[1]
    cells, piece = frame.copy(), pieces.at(groups, frame)
    off = np.flatnonzero(piece == 0)
    while len(off):  # each step is a cell nearer the outside, where the way ends
        cells[off] += STEPS[_way_out(sense, cells[off], rows[off])]
        piece[off] = pieces.at(groups[off], cells[off])
        off = off[(piece[off] == 0) & (enclosed.at(groups[off], cells[off]) > 0)]
    return piece


def _way_out(sense: Perception, frame: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """For robots at `frame`, the way to the neighbouring cell nearest the shape's outside,
    counting the pockets it encloses as inside (ties by direction number)."""
    enclosed = _depths(sense.blueprint)[1]
    groups = sense.group[rows]
    depth = np.stack([enclosed.at(groups, frame + STEPS[d]) for d in range(1, len(STEPS))])
    return depth.argmin(axis=0) + 1


def _relay_seekers(
    sense: Perception, memory: Memory, calling: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A robot that calls open cells to it (`calling`, see `_cut_off`) that each robot knows
    of, and hops to it (0: itself, FAR: none): its own cell, or the one its neighbours tell of
    with fewest hops. One that gets a goal stops calling, and the news of it dies out by
    counting up to `CALL_REACH`."""
    me, msg = sense.owner, sense.message
    news = sense.heard & sense.kin & ~sense.seed & (msg[:, SEEKER_HOPS] < CALL_REACH)
    news &= memory.localised[me]
    best = best_per_robot(len(sense), me, msg[:, SEEKER_HOPS], news)
    told = (best >= 0) & ~calling
    cell, hops = memory.frame.copy(), np.where(calling, 0, FAR)
    cell[told] = msg[best[told], SX : SY + 1]
    hops[told] = msg[best[told], SEEKER_HOPS] + 1
    return cell, hops


def _deeper(
    sense: Perception,
    memory: Memory,
    occupied: np.ndarray,
    seeker: np.ndarray,
    seeker_hops: np.ndarray,
) -> np.ndarray:
    """Per robot, the way to an adjacent open cell deeper in the shape than its own, or 0.
    Deeper, for a robot with a goal that hears of a robot calling open cells to it
    (`_relay_seekers`), unless it rests on a cell a reshape kept (see `_reshaped`): farther
    from that robot, so stepping there brings the open cell one
    step nearer it, and open cells travel through a formed shape to robots it walls off from
    them. A horseshoe's last two cells, open on its outer edge, waited for ever for the two
    robots in its bay; at 10,000 robots the spare ones jammed on the far side of the letter
    S's arm, 28 cells thick, from the open cells on its bay side. Otherwise deeper is by
    depth (steps to the nearest cell outside the shape), so holes surface at the rim where
    spare robots reach them, and robots that claim the rim of new rows never wall the inner
    row in. Filling from the inside out, and open cells that travel, are our lattice
    additions, not the paper's. Each step raises the summed depth of occupied cells or
    brings an open cell nearer a calling robot, which stops calling once it has a goal."""
    depth = _depth(sense.blueprint)
    drawn = memory.has_goal & (seeker_hops < FAR) & ~memory.kept

    def value(cells: np.ndarray) -> np.ndarray:
        inside = depth.at(sense.group, cells)
        farther = _apart(cells, seeker) + 1  # 0 stays for outside the shape
        return np.where(inside > 0, np.where(drawn, farther, inside), 0)

    best = value(memory.frame)
    inside = best > 0
    talk = sense.heard & sense.kin & ~sense.seed
    held = _held_beside(sense.owner, talk, sense.message, memory.frame)
    way = np.zeros(len(sense), dtype=np.int64)
    for direction in range(1, len(STEPS)):
        there = value(memory.frame + STEPS[direction])
        better = ~occupied[:, direction] & ~held[:, direction] & (there > best)
        best, way = np.where(better, there, best), np.where(better, direction, way)
    return np.where(inside, way, 0)


@njit
def _held_beside(
    owner: np.ndarray, talk: np.ndarray, msg: np.ndarray, frame: np.ndarray
) -> np.ndarray:  # pragma: no cover (compiled)
    """``(n, len(STEPS))``: whether a neighbour each robot hears (`talk`) holds the cell one
    step away in each direction as its goal. As numpy passes, gathering every robot's frame
    for each of its entries, it took a tenth of `local-swap`'s step at 10,000 robots."""
    held = np.zeros((len(frame), len(STEPS)), dtype=np.bool_)
    for e in range(len(owner)):
        m = owner[e]
        dx, dy = msg[e, GX] - frame[m, 0], msg[e, GY] - frame[m, 1]
        if talk[e] and msg[e, HAS] == 1 and abs(dx) + abs(dy) == 1:
            held[m, DIRECTION_OF[dx + 1, dy + 1]] = True
    return held


def _depth(blueprint: Blueprint) -> Boxes:
    """Each shape cell's steps to the nearest cell outside the shape (see `_depths`)."""
    return _depths(blueprint)[0]


@functools.lru_cache(maxsize=4)
def _depths(blueprint: Blueprint) -> tuple[Boxes, Boxes]:
    """Per group, the low corner of its shape's box (less one) and the taxicab distance of each
    cell to the nearest cell outside the shape (0 outside), in a box padded by one; and the same
    counting the pockets the shape encloses as inside (0 only where a robot is free to walk
    away, see `_leaving`). The seeds count as inside: no robot comes in past them, and a cell
    they wall off from the outside must be filled from deeper in. They sit on fixed cells of the
    seed frame (the frame is theirs), so every robot knows them as it knows the bitmap. So do
    pockets of outside that shape and seeds enclose (a cut corner beside the seeds)."""
    out, enclosed = [], []
    for shape in blueprint.cells:
        cells = np.concatenate([shape, SEED_CELLS]) if len(shape) else shape
        low = cells.min(axis=0) - 1 if len(cells) else np.zeros(2, dtype=np.int64)
        size = cells.max(axis=0) - low + 2 if len(cells) else np.ones(2, dtype=np.int64)
        grid = np.zeros(size, dtype=bool)
        grid[cells[:, 0] - low[0], cells[:, 1] - low[1]] = True
        inside = scipy.ndimage.binary_fill_holes(grid)
        depth = scipy.ndimage.distance_transform_cdt(inside, metric="taxicab")
        out.append((low, np.where(grid, depth, 0)))
        enclosed.append((low, depth))
    return Boxes(out), Boxes(enclosed)


def localise(sense: Perception, memory: Memory) -> None:
    """Dead-reckon localised robots by their odometry; a robot that is not localised takes
    its frame cell from its nearest seed or localised neighbour at rest (that one's frame cell
    less the offset sensed from its own cell's centre, which a robot under way knows from its
    odometer), when the offset reads as whole cells. Robots that took their bearings only at
    rest followed the others to the shape under way most of the time: 820 of the 1,018-robot
    S were still lost at step 100 and 454 at step 200 (seed 0; now 181 and none).

    Entries' rows are gathered by `np.take` and the messages a field at a time: numpy 2.4's
    ``array[rows]`` of a 2-D array, the whole message of every entry of a lost robot, took
    4 ms of `local-swap`'s step at 10,000 robots (see `LocalControl.perceive`)."""
    # not a masked add: numpy 2.4 copies a 2-D array's masked rows one by one, 5 times slower
    memory.frame += np.where(memory.localised[:, None], sense.moved, 0)
    rows = np.flatnonzero(~memory.localised[sense.owner])  # the entries of robots still lost
    owner, msg, seed = sense.owner[rows], sense.message, sense.seed[rows]
    own = sense.progress[owner, None] * np.take(STEPS, sense.heading[owner], axis=0)
    offset = np.take(sense.offset, rows, axis=0) + own  # from its cell's centre
    cells = np.rint(offset).astype(np.int64)
    whole = _within(offset - cells, 0.25, strict=True)
    heard = sense.heard[rows] & sense.kin[rows]
    robot = heard & ~seed & (msg[rows, LOCALISED] == 1) & (msg[rows, STAYS] == 1)
    said = np.column_stack([msg[rows, X], msg[rows, Y]])
    reference = np.where(seed[:, None], np.take(sense.seed_frame, rows, axis=0), said)
    usable = whole & (robot | heard & seed)
    first = best_per_robot(len(sense), owner, np.zeros(len(usable)), usable)
    found = first >= 0
    memory.frame[found] = (reference - cells)[first[found]]
    memory.localised |= found


def _hops(sense: Perception, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
    """Each robot's hops to a localised robot (a seed counts; FAR: none, or a count that rose
    `CLIMB` hops within twice as many steps), and the direction of its neighbour nearest one
    (0 if none is nearer than itself)."""
    heard_hops = np.where(
        sense.seed, 0, np.where(sense.kin & ~sense.seed, sense.message[:, HOPS], FAR)
    )
    heard_hops = np.where(sense.heard & sense.kin, heard_hops, FAR)
    heard_hops[~sense.seed & (sense.message[:, LOCALISED] == 0) & (heard_hops == 0)] = FAR
    best = best_per_robot(len(sense), sense.owner, heard_hops, np.ones(len(heard_hops), bool))
    found = best >= 0
    nearest = np.full(len(sense), FAR, dtype=np.int64)
    nearest[found] = heard_hops[best[found]]
    hops = np.where(memory.localised, 0, np.minimum(nearest + 1, FAR))
    memory.low_age += 1
    fresh = (hops <= memory.low_hops) | (memory.low_age > 2 * CLIMB)
    memory.low_hops = np.where(fresh, hops, memory.low_hops)
    memory.low_age[fresh] = 0
    hops[hops - memory.low_hops >= CLIMB] = FAR  # counting up to infinity: no way back
    offset = np.zeros((len(sense), 2))
    offset[found] = sense.offset[best[found]]
    along_x = np.abs(offset[:, 0]) >= np.abs(offset[:, 1])
    way = np.where(along_x, np.where(offset[:, 0] > 0, 1, 2), np.where(offset[:, 1] > 0, 3, 4))
    closer = found & (nearest < FAR) & (np.abs(offset).max(axis=1) >= 1.5)
    return hops, np.where(closer, way, 0)


@functools.lru_cache(maxsize=1)
def _cells(sense: Perception) -> np.ndarray:
    """Each neighbour's offset rounded to whole cells, worked out once a step (five of the
    program's parts use it)."""
    return np.rint(sense.offset).astype(np.int64)


def _occupied(sense: Perception, counted: np.ndarray | None = None) -> np.ndarray:
    """``(n, 5)``: whether something sits in the cell one step in each direction (a
    neighbour whose offset rounds to that step; of the entries `counted`, if given)."""
    cells = _cells(sense)
    occupied = np.zeros((len(sense), len(STEPS)), dtype=bool)
    beside = _apart(cells, STEPS[0]) == 1
    unit = np.flatnonzero(beside if counted is None else beside & counted)
    occupied[sense.owner[unit], DIRECTION_OF[cells[unit, 0] + 1, cells[unit, 1] + 1]] = True
    return occupied


def _note_walls(sense: Perception, memory: Memory, occupied: np.ndarray) -> None:
    """A move asked for last step that did not happen met something a robot cannot sense (the
    arena's edge, or a cell another robot took first): treat that way as blocked now, so a
    detour turns back at a wall instead of pushing into it for ever."""
    failed = np.flatnonzero(sense.ready & (memory.asked > 0) & _same(sense.moved, STEPS[0]))
    occupied[failed, memory.asked[failed]] = True


def _leaving_ahead(sense: Perception) -> np.ndarray:
    """Entries of a neighbour that is leaving the cell beside the robot, straight away from it:
    under way (by its message), its offset rounding to that cell's and past the cell's centre
    (one moving across the robot's way stays level with it). The robot may follow it in: the
    swarm queues a claim on a cell whose robot leaves it the same way (`Swarm.followable`),
    and refuses any other. A robot at rest whose asks were refused says it does not stay too,
    and with noisy distances one in two looked past its cell's centre: the robot behind asked
    for its cell, refused, step after step, and never went round (a fuzz case of 88 cells
    stopped at 84 %)."""
    rows = np.flatnonzero(sense.heard & ~sense.seed & (sense.message[:, MOVING] == 1))
    cells = _cells(sense)[rows]
    along = np.einsum("ij,ij->i", sense.offset[rows], cells)  # how far along to that cell
    leaving = np.zeros(len(sense.owner), dtype=bool)
    leaving[rows] = (_apart(cells, STEPS[0]) == 1) & (along > 1.0)
    return leaving


def _plan(
    sense: Perception,
    delta: np.ndarray,
    occupied: np.ndarray,
    going: np.ndarray,
    radius: float,
    counted: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """A robot's first step on the shortest free path, within the square it senses, to the
    free cell there nearest its goal (0: none nearer than where it is, not going, or under way,
    where `_cruise` decides and the path went unused: 5 ms of a 10,000-robot step); and the
    straight way to the goal, the longer axis first. A robot that only stepped straight at its
    goal took the long way round the shape half the time (it picked a side by coin when
    blocked), and the last open cell of an 8 by 8 square waited hundreds of steps for it.
    It plans over the cells it can sense only, and never straight back the way it came:
    counting cells out of range as free sent robots toward them and back once they came in
    sight, and two robots that each stepped aside for the other did so for ever.

    A neighbour blocks it only if `counted`: not one leaving its cell beside the robot straight
    away from it (`_leaving_ahead`), which the robot may follow in. A line of robots, each a
    cell short of its goal and the first beside an open cell, used to move one at a time, each
    starting only once the cell ahead was empty: about five steps a robot, where followers
    start a step or two apart. Many of the last robots of a shape were in such lines. Over
    issue 30's five shapes at 1,000 robots, seeds 0 to 9, the median steps over the makespan
    bound fell from 7.26 to 7.19 with this, a little on each shape (the horse's 10.1 to 9.8)."""
    x = np.where(delta[:, 0] > 0, 1, np.where(delta[:, 0] < 0, 2, 0))
    y = np.where(delta[:, 1] > 0, 3, np.where(delta[:, 1] < 0, 4, 0))
    first = np.where(np.abs(delta[:, 0]) >= np.abs(delta[:, 1]), x, y)
    planning = np.flatnonzero(going & sense.ready)
    beyond = _disc_index(radius) < 0
    chosen = _first_steps(planning, sense.start, _cells(sense), counted, delta, occupied, beyond)
    return chosen, np.where(going, first, 0)


@njit
def _first_steps(
    rows: np.ndarray,
    start: np.ndarray,
    cells: np.ndarray,
    counted: np.ndarray,
    delta: np.ndarray,
    occupied: np.ndarray,
    beyond: np.ndarray,
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_plan`'s paths, robot by robot (`rows`): in its square (`beyond`: the cells out of
    sensing range), blocked where a `counted` neighbour's rounded offset (`cells`, CSR by
    `start`) or `occupied` says, the fewest moves to each cell breadth first; the cell
    nearest the goal (`delta` away), then fewest moves, the first in row order; and the first
    move of a shortest way there, through the first cell in move order a move nearer at each
    cell. Every robot's square at once, as numpy passes round a compiled breadth-first one,
    cost the 10,000-robot S 2.8 ms a step; this takes 0.9 ms. The square has a blocked
    border, so a move needs no test for the square's edges."""
    side = len(beyond)
    reach, area, width = side // 2, side * side, side + 2
    centre = (reach + 1) * width + reach + 1  # cell (x, y) of the square is centre + x * width + y
    moves = STEPS[:, 0] * width + STEPS[:, 1]
    bordered = np.ones(width * width, dtype=np.bool_)
    for x in range(side):
        for y in range(side):
            bordered[centre + (x - reach) * width + y - reach] = beyond[x, y]
    blocked = np.empty(width * width, dtype=np.bool_)
    steps = np.empty(width * width, dtype=np.int64)
    queue = np.empty(area, dtype=np.int64)
    chosen = np.zeros(len(occupied), dtype=np.int64)
    for r in rows:
        blocked[:] = bordered
        for e in range(start[r], start[r + 1]):
            if counted[e] and abs(cells[e, 0]) <= reach and abs(cells[e, 1]) <= reach:
                blocked[centre + cells[e, 0] * width + cells[e, 1]] = True
        for direction in range(1, len(STEPS)):
            if occupied[r, direction]:
                blocked[centre + moves[direction]] = True
        steps[:] = -1
        steps[centre] = 0  # the robot's own cell, blocked or not
        queue[0], head, tail = centre, 0, 1
        while head < tail:
            cell = queue[head]
            head += 1
            for direction in range(1, len(STEPS)):
                there = cell + moves[direction]
                if not blocked[there] and steps[there] < 0:
                    steps[there] = steps[cell] + 1
                    queue[tail] = there
                    tail += 1
        dx, dy = delta[r, 0], delta[r, 1]
        best, best_score = centre, BIG
        for x in range(-reach, reach + 1):
            for y in range(-reach, reach + 1):
                cell = centre + x * width + y
                if steps[cell] >= 0:
                    score = (abs(dx - x) + abs(dy - y)) * area + steps[cell]
                    if score < best_score:
                        best, best_score = cell, score
        if best_score // area >= abs(dx) + abs(dy):
            continue  # no cell it reaches is nearer its goal than its own
        cell = best
        while steps[cell] > 0:  # back through the first cell a move nearer, to its own cell
            for direction in range(1, len(STEPS)):
                if steps[cell - moves[direction]] == steps[cell] - 1:
                    cell, chosen[r] = cell - moves[direction], direction
                    break
    return chosen


def _go_round(
    memory: Memory,
    delta: np.ndarray,
    preferred: np.ndarray,
    first: np.ndarray,
    occupied: np.ndarray,
    ready: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of robots on their way, going round what blocks them like a bug algorithm: after
    `PATIENCE` steps blocked, a robot steps sideways (toward the goal if it lies off to one
    side, else a random side) and keeps that way until the way it was blocked in is free,
    turning back when the side is blocked too. A detour ends too once that way no longer
    leads to the goal (a trade changed it): one robot kept going round for a way that led
    nowhere for hundreds of steps."""
    rows = np.arange(len(first))
    memory.detour[(STEPS[memory.blocked_way] * delta).sum(axis=1) <= 0] = 0
    blocked = ready & (preferred == 0) & (first > 0)
    memory.waited = np.where(blocked & (memory.detour == 0), memory.waited + 1, 0)
    start = blocked & (memory.waited > PATIENCE)
    off = np.where(first <= 2, delta[:, 1], delta[:, 0])  # < 0: the side numbered higher
    coin = rng.random(len(first)) < 0.5
    sideways = np.where(first <= 2, 3, 1) + np.where(off == 0, coin, off < 0)
    memory.blocked_way = np.where(start, first, memory.blocked_way)
    memory.detour = np.where(start, sideways, memory.detour)
    memory.waited[start] = 0
    on_detour = ready & (memory.detour > 0)
    way, side = memory.blocked_way, memory.detour
    clear = ~occupied[rows, way]
    onward = ~occupied[rows, side]
    memory.detour = np.where(on_detour & ~clear & ~onward, REVERSE[side], memory.detour)
    moves = np.where(on_detour, np.where(clear, way, np.where(onward, side, 0)), preferred)
    memory.detour[on_detour & clear] = 0
    memory.detour[~ready & (preferred == 0) & (first == 0)] = 0
    return np.where(ready, moves, 0)


def _choose_partner(
    sense: Perception,
    memory: Memory,
    preferred: np.ndarray,
    target: np.ndarray,
    seeking: np.ndarray,
    news: np.ndarray,
    news_hops: np.ndarray,
    rested: np.ndarray,
    silent: np.ndarray,
) -> np.ndarray:
    """The neighbour each robot wants to trade goals with next step (its number), or -1: one that
    shortens their summed squared distance, one at rest in its way (robots that each wait for
    the next one's cell, in a ring, trade their way out of it), or (a robot without a goal, see
    `PUSH_HOPS`) one resting in its way nearer an open cell, which gives up its cell and goes on
    toward the open one, or (a robot walled in a pocket, see `_leaving`) one resting in its way
    out, which gives up its cell and goes on out.

    Squared, as the least total squared distance (CAPT) is for the planners: its assignment
    has no two robots whose straight ways cross, and every trade that shortens it lowers a sum
    of whole numbers, so trades end. Summed in steps, a trade between robots whose ways cross
    at right angles, or with a robot resting on its goal straight ahead, gained nothing: robots
    met, asked, held still and traded in turn (the 1,000-robot disc, seed 0: 22,734 trades in
    685 steps, 16,334 of them gaining nothing, most robots standing inside the disc short of
    their goals by step 300). Squared, such trades shorten the way, so both robots want them in
    the same step, under way too: over the five shapes of issue 30 at 1,000 robots, seeds 0 to
    4, 90 % of the cells were filled by 2.5 to 3.6 times the makespan bound, against 3.6 to 7.3.

    A trade that shortens the summed squared distance is agreed with a neighbour on the move
    too (one at rest holds still for it): two robots that met head-on in a corridor each
    stepped aside for the other, in step, and never once both stood still to trade. A robot
    under way agrees such a trade too, and goes on while it does (only these: the other kinds
    are for a robot blocked where it rests). When robots chose only at rest, a robot that asked
    one under way held still while it passed by: on the 1,018-robot S (seed 0) 17,076 of 84,507
    asks went unanswered so, robot-steps still that were a twentieth of all the steps robots
    spent short of their goals; over the five shapes of issue 30 at
    1,000 robots, seeds 0 to 9, the median steps over the makespan bound fell from 8.1 to 7.3
    with this, and the median distance over the least from 1.64 to 1.52. A robot on its way to
    its goal trades with one resting on its own goal beside it and toward its goal even when it
    could walk round it (Wang and Rubenstein's swap when blocked): the goal passes into the
    formed robots, each of them a cell nearer it, instead of its robot walking round the shape's
    edge at a stop on every cell (the 1,018-robot S, seeds 0 to 4: 868 to 1,770 steps before,
    667 to 922 after). A robot never trades for a goal it knows a third robot rests on (see
    `_held_twice`), nor, resting on its own goal, for one it sees a robot on that it does not
    hear (`_silent_cells`): a robot that held a goal under a stalled robot traded it into the
    formed shape, whose robot then left its cell for it.

    Of equal scores a robot takes the lowest-numbered neighbour, the same order on both ends of
    every pair, so the best pair among robots still for each other always trades. Preferring the
    neighbour that had asked for it left five robots twenty cells from a 1,018-robot S passing
    the asks round a ring, each wanting one that wanted another, for 17,000 steps. A trade that
    shortens nothing takes two steps (one asks, the other answers), and by number two robots of
    a 10,000-robot S asked each other in turn, never in the same step, for 3,000 steps; the
    nearest first instead (reach order) lets robots on cells a reshape keeps trade away from
    them."""
    me, msg = sense.owner, sense.message
    talk = sense.heard & sense.kin & ~sense.seed & (msg[:, LOCALISED] == 1)
    talk &= memory.localised[me]
    return _partners(
        me, np.flatnonzero(talk), msg, sense.number, sense.ready, memory.has_goal, memory.goal,
        memory.frame, target, seeking, preferred, news, news_hops, memory.leaving, memory.calling,
        _pushed_on(memory), memory.partner, memory.since_trade, memory.kept, rested, silent,
        memory.unsure > 0, sense.radius,
    )  # fmt: skip


@njit
def _partners(
    owner: np.ndarray,
    rows: np.ndarray,
    msg: np.ndarray,
    number: np.ndarray,
    ready: np.ndarray,
    has_goal: np.ndarray,
    goal: np.ndarray,
    frame: np.ndarray,
    target: np.ndarray,
    seeking: np.ndarray,
    preferred: np.ndarray,
    news: np.ndarray,
    news_hops: np.ndarray,
    leaving: np.ndarray,
    calling: np.ndarray,
    pushed_on: np.ndarray,
    partner: np.ndarray,
    since_trade: np.ndarray,
    kept: np.ndarray,
    rested: np.ndarray,
    silent: np.ndarray,
    unsure: np.ndarray,
    radius: float,
) -> np.ndarray:  # pragma: no cover (compiled)
    """`_choose_partner` over the entries `rows`, in reach order: each robot's score for the
    neighbour that sent the entry, and the number of the one it scores highest (of equal
    scores the lowest-numbered, then the nearest), or -1. As sixty numpy passes over every
    entry it took a third of `local-swap`'s step at 10,000 robots."""
    wants = np.full(len(has_goal), -1, dtype=np.int64)
    best = np.zeros(len(has_goal), dtype=np.int64)  # the score of the one it wants
    for e in rows:
        m = owner[e]
        mx, my, tx, ty = frame[m, 0], frame[m, 1], msg[e, X], msg[e, Y]
        mgx, mgy, tgx, tgy = goal[m, 0], goal[m, 1], msg[e, GX], msg[e, GY]
        my_has, their_has = has_goal[m], msg[e, HAS] == 1
        now = traded = 0
        if my_has:
            now += (mx - mgx) ** 2 + (my - mgy) ** 2
            traded += (tx - mgx) ** 2 + (ty - mgy) ** 2
        if their_has:
            now += (tx - tgx) ** 2 + (ty - tgy) ** 2
            traded += (mx - tgx) ** 2 + (my - tgy) ** 2
        gain = now - traded
        asked = msg[e, WANTS] == number[m]
        wx, wy = target[m, 0] - mx, target[m, 1] - my
        beside = abs(tx - mx) + abs(ty - my) == 1
        blocked = (my_has or seeking[m]) and preferred[m] == 0 and abs(wx) + abs(wy) > 0
        ahead = np.sign(tx - mx) * np.sign(wx) > 0 or np.sign(ty - my) * np.sign(wy) > 0
        resting_there = their_has and tx == tgx and ty == tgy
        walking = my_has and abs(wx) + abs(wy) > 0
        in_the_way = (blocked or (walking and resting_there)) and beside and ahead
        push = in_the_way and resting_there and not my_has
        push = push and (msg[e, OPEN_HOPS] <= PUSH_HOPS or leaving[m])
        push = push and (calling[m] or pushed_on[m] or leaving[m])  # on down the chain
        ox, oy = news[m, 0], news[m, 1]
        nearer = abs(mx - ox) + abs(my - oy) < abs(tx - ox) + abs(ty - oy)
        pushed = asked and my_has and not their_has and mx == mgx and my == mgy
        pushed = pushed and ((news_hops[m] <= PUSH_HOPS and nearer) or msg[e, LEAVING] == 1)
        fair = gain == 0 and (asked or in_the_way)
        ahead = np.sign(mx - tx) * np.sign(tgx - tx) > 0 or np.sign(my - ty) * np.sign(tgy - ty) > 0
        in_their_way = asked and their_has and beside and ahead
        # a robot in its way, or one it stands in the way of, before one that only asked: a
        # robot that answered the ask of one robot three cells off and was asked by the one in
        # its way, in turn, never traded. Both ends of a blocked pair score it the same, so in a
        # ring of robots each on the next one's goal the lowest-numbered pair wants each other;
        # scoring only its own blocked way, each wanted the next for good (9,946-robot S, 317
        # robots, from step 3,900 on)
        score = 0
        if gain > 0:
            score = 4 * gain
        elif not ready[m]:
            continue  # under way, only a trade that shortens the way
        elif msg[e, STAYS] == 1 and (fair or push or pushed):
            score = 2 if fair and (in_the_way or in_their_way) else 1
        if score <= 0:  # the checks below cost more than the score, and most score nothing
            continue
        same = my_has == their_has and (not my_has or (mgx == tgx and mgy == tgy))
        again = msg[e, NUMBER] == partner[m] and since_trade[m] < TABU
        settled = my_has and mx == mgx and my == mgy
        key = _key_of(m, tgx, tgy)
        held = their_has and not resting_there and _known(key, rested)
        held = held or (settled and their_has and _known(key, silent))
        # a trade sends a robot resting on its goal to the other's goal: only
        # where it sees that goal or knows the shape unfinished (current news of an open cell
        # other than its own, which it may have just claimed), and both ends know it. A spare
        # that claimed a cell whose holder was out of range left that holder a goal already
        # filled; traded on, it reached a robot in the formed shape that left its cell for it
        # (nor a goal that may be held twice, `_unsure`)
        told = news_hops[m] < FAR and not (ox == mgx and oy == mgy) and msg[e, UNSURE] == 0
        out_of_sight = np.hypot(float(tgx - mx), float(tgy - my)) > radius
        held = held or (settled and their_has and not told and out_of_sight)
        told = msg[e, OPEN_HOPS] < FAR and not (msg[e, OX] == tgx and msg[e, OY] == tgy)
        told = told and not unsure[m]
        out_of_sight = np.hypot(float(mgx - tx), float(mgy - ty)) > radius
        held = held or (resting_there and my_has and not told and out_of_sight)
        # a robot on a cell a reshape kept trades only with one leaving a pocket, and both ends
        # know it (a one-sided refusal would leave the other waiting for it for good)
        refused = (kept[m] and msg[e, LEAVING] == 0) or (msg[e, KEPT] == 1 and not leaving[m])
        if same or again or held or refused:
            continue
        if wants[m] < 0 or score > best[m] or (score == best[m] and msg[e, NUMBER] < wants[m]):
            wants[m], best[m] = msg[e, NUMBER], score
    return wants


def _trade(sense: Perception, memory: Memory) -> None:
    """Robots that wanted each other last step, and hear each other now, swap goals. One
    that gives its goal to a robot leaving a pocket was pushed out, and leaves too (see
    `_leaving`)."""
    # only the entries of robots that want a partner (few, once most rest), field by field
    me, msg = sense.owner, sense.message
    asking = np.flatnonzero((memory.wants >= 0)[me])
    mutual = sense.heard[asking] & sense.kin[asking] & ~sense.seed[asking]
    mutual &= msg[asking, NUMBER] == memory.wants[me[asking]]
    mutual &= msg[asking, WANTS] == sense.number[me[asking]]
    entries = asking[mutual]
    me = me[entries]
    memory.gave[me] = memory.has_goal[me]
    memory.given[me] = memory.goal[me]
    memory.has_goal[me] = msg[entries, HAS] == 1
    memory.goal[me] = msg[entries, GX : GY + 1]
    memory.detour[me] = 0  # a detour for the old goal
    memory.came[me] = 0  # the way back may lead to the new one
    memory.since_trade += 1
    memory.partner[me] = msg[entries, NUMBER]
    memory.leaving[me] = msg[entries, LEAVING] == 1  # pushed out: it leaves too
    memory.since_trade[me] = 0


def _silent_cells(sense: Perception, memory: Memory) -> np.ndarray:
    """Sorted keys (`_key`) of each robot and the frame cells it sees a robot on that it does
    not hear. A stalled robot is silent and holds its cell for good; a live one goes unheard
    now and then when messages are lost."""
    me = sense.owner
    unheard = ~sense.heard & ~sense.seed
    cells = memory.frame[me[unheard]] + _cells(sense)[unheard]
    return np.sort(_key(me[unheard], cells))


def _give_up_to_the_silent(sense: Perception, memory: Memory, silent: np.ndarray) -> None:
    """Give up a goal whose cell a robot it does not hear has sat on for `SILENCE` steps: a
    goal under a stalled robot can never be reached, and a robot that kept it waited beside
    it for ever. A live robot goes unheard that long only with chance ``msg_loss **
    SILENCE``, and then its cell is merely open again to seekers. Only a step at rest, when
    offsets are whole cells, clears the count."""
    robots = np.arange(len(sense))
    seen = memory.localised & memory.has_goal & _among(_key(robots, memory.goal), silent)
    memory.silence = np.where(seen, memory.silence + 1, np.where(sense.ready, 0, memory.silence))
    memory.has_goal &= memory.silence < SILENCE


def _unheard_too_long(sense: Perception, memory: Memory, hops: np.ndarray) -> np.ndarray:
    """Robots without bearings that have heard no hop count (`_hops`) for longer than the
    count takes to cross a swarm of their shape's size at the density they sense (its
    diagonal in hops), or that sense nobody: they roam (`_roam`); the others wait for it.
    A count spreads a hop a step from the seeds, and at the first step every robot beyond the
    seeds' range hears none: roaming at once, the far robots of the 1,018-robot S walked off
    in random directions until the count reached them, and came back (seed 1: 15,400 cells
    walked without bearings, against 2,406 with the wait). Waiting on the robots it senses
    without a bound, two robots cut off together waited on each other for good; waiting
    twice the crossing, three robots cut off in a corner of the 1,000-robot star's arena set
    out when the swarm had left for the shape, and searched the empty arena for 2,000 steps."""
    memory.unheard = np.where(hops >= FAR, memory.unheard + 1, 0)
    near = _near(sense)
    return (hops >= FAR) & ((near == 0) | (memory.unheard > _crossing(sense)))


@functools.lru_cache(maxsize=1)
def _near(sense: Perception) -> np.ndarray:
    """How many robots each robot senses."""
    return np.bincount(sense.owner[sense.kin & ~sense.seed], minlength=len(sense))


@functools.lru_cache(maxsize=1)
def _crossing(sense: Perception) -> np.ndarray:
    """Per robot, the steps a hop count takes to cross a swarm of its shape's size at the
    density it senses: its diagonal in hops."""
    density = (_near(sense) + 1) / (np.pi * sense.radius**2)
    span = np.sqrt(sense.blueprint.count(sense.group) / density)  # the swarm's side, in cells
    return np.sqrt(2) * span / sense.radius


def _roam(
    sense: Perception,
    memory: Memory,
    occupied: np.ndarray,
    roaming: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of robots that have heard of no localised robot for long (`_unheard_too_long`):
    they sweep the arena in strips. A robot crosses it (`crossing`: first the way the hop count
    last led it, see `_hops`, else a random one) until it meets the arena's edge (a move that
    failed where it senses no robot), shifts sideways (`sweep`) by a strip's width
    (`_strip`), and crosses back; at a side edge it crosses along the edge, then sweeps back
    the other way. Shifting back from the edge a whole strip instead, it swept the same lines
    for good and never the band along the edge: a robot alone in a 40 by 40 arena never found
    the seeds in its corner. A robot in its
    way makes it step aside at random once, not change its plan. Everything with bearings ends
    in the shape, so a sweep finds it in a few crossings. Walks of 20 cells or so each in a
    random way instead left the robots that lost the count in the corners of the 1,000-robot
    disc's arena, once the swarm had gone to the shape, searching for up to 1,300 steps: such
    a walk needs the area squared to cover it, and gathers at the edges. Ways are chosen at
    rest: a robot on the move senses its neighbours from between two cells; under way it
    cruises, and brakes at the end of a shift (see `act`)."""
    rows = np.flatnonzero(roaming & sense.ready)
    way, crossing, sweep = memory.roam[rows], memory.crossing[rows], memory.sweep[rows]
    shift = memory.shift[rows]
    walls = occupied[rows] & ~_crowded(sense, roaming)[rows]
    each = np.arange(len(rows))
    fresh = crossing == 0
    crossing[fresh] = np.where(way[fresh] > 0, way[fresh], rng.integers(1, 5, fresh.sum()))
    side = rng.random(fresh.sum()) < 0.5
    sweep[fresh] = np.where(side, RIGHT[crossing[fresh]], LEFT[crossing[fresh]])
    way[fresh] = crossing[fresh]
    shifting = way == sweep
    at_edge = shifting & walls[each, sweep]
    sweep[at_edge] = REVERSE[sweep[at_edge]]  # it crosses along the edge, then sweeps back
    way[shifting & (at_edge | (shift <= 0))] = crossing[shifting & (at_edge | (shift <= 0))]
    met = (way == crossing) & walls[each, crossing]
    crossing[met] = REVERSE[crossing[met]]  # across: shift, then cross back
    way[met] = sweep[met]
    shift[met] = _strip(sense.blueprint, sense.radius)[sense.group[rows]][met]
    memory.roam[rows], memory.crossing[rows], memory.sweep[rows] = way, crossing, sweep
    memory.shift[rows] = shift
    moves = memory.roam[roaming].copy()
    blocked = np.flatnonzero(occupied[rows, way])
    moves[np.searchsorted(np.flatnonzero(roaming), rows[blocked])] = _random_free(
        occupied[rows[blocked]], rng
    )
    return moves


def _crowded(sense: Perception, robots: np.ndarray) -> np.ndarray:
    """``(n, 5)``: for `robots`, whether a neighbour is within a cell and a half of the cell one
    step in each direction. A move that failed where none is met the arena's edge; one that
    failed beside a robot under way lost the cell to it. Counting only neighbours on the cell
    itself, a robot sweeping for the others took a robot moving in for the edge, and turned
    back four cells from them. (Beside another robot, a robot does not see the edge ahead: it
    steps aside at random until the two part.)"""
    entries = np.flatnonzero(robots[sense.owner])
    crowded = np.zeros((len(sense), len(STEPS)), dtype=bool)
    for way in range(1, len(STEPS)):
        close = entries[_within(sense.offset[entries] - STEPS[way], 1.5)]
        crowded[sense.owner[close], way] = True
    return crowded


@functools.lru_cache(maxsize=4)
def _strip(blueprint: Blueprint, radius: float) -> np.ndarray:
    """Per group, the width in cells of the strips robots sweep the arena in (`_roam`): half
    the shape's shorter side, so two strips cross a round shape and one its narrower parts, but
    no less than a sensing range's span (2r + 1 cells), over which one strip's robot senses
    everything: narrower strips would sense the same cells twice."""
    sides = [np.ptp(cells, axis=0).min() + 1 if len(cells) else 1 for cells in blueprint.cells]
    return np.maximum(np.array(sides, dtype=np.int64) // 2, 2 * int(radius) + 1)


def _random_free(occupied: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random direction whose cell is free for each robot, or 0 if none is."""
    noise = rng.random(occupied.shape)
    noise[:, 0] = -1.0
    noise[occupied] = -1.0
    choice = noise.argmax(axis=1)
    return np.where(noise.max(axis=1) > 0, choice, 0)

"""Working out where a robot is, in its seed frame, from the seeds and its neighbours.

Seeds broadcast their frame cells; a robot that knows its frame cell broadcasts it, the way it
is moving and how far along, and whether it stays there next step. A robot that does not know
where it is takes its cell from the nearest seed or such a neighbour (see `localise`), and from
then on keeps it by odometry. So knowledge spreads outward from the seeds a sensing radius a
step, through robots at rest and on the move. A robot that knows nothing walks toward one that
does, or roams straight across the arena until it sees one.

A program using these keeps memory slots ``localised``, ``frame`` (2), ``anchor`` and
``roam``, and broadcasts fields ``localised``, ``cell`` (2), ``heading`` (the move it is making
or starting, 0 if it stays), ``progress`` (in 1/`FIXED` cells), ``stays`` and ``anchor``
(`anchor_said`).
"""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.local import Memory
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Perception
from swarmshape.strategies.skills import relay
from swarmshape.strategies.skills.view import View

WHOLE = 0.25
"""How far from whole cells a position worked out from a neighbour may be and still be read
as a cell (distance noise of up to a quarter of a cell)."""

FIXED = 1024
"""A robot's progress along its heading is broadcast in 1/FIXED cells."""


def localise(sense: Perception, memory: Memory, said: SimpleNamespace) -> None:
    """Dead-reckon localised robots by their odometry; fix the others that can, from the
    nearest seed or localised neighbour, at rest or on the move.

    A neighbour's broadcast tells its cell, the way it is going and how far along it was; by
    now it has gone on by less than a cell, and the fraction of the sensed offset along its
    way tells how far: so the listener's cell is that neighbour's position less the sensed
    offset less its own progress, when that reads as a whole cell. A neighbour near a cell's
    centre that said it was under way may have just arrived or not yet set off (a move asked
    for can fail), so it is used only when it said it stays.

    A localised robot at rest takes the cell that most of the seeds it senses put it on, or,
    with none in sight, most of its localised neighbours at rest *nearer the seeds*, when
    more of them say so than say it is where it thinks. A fix from a neighbour that turned as
    it was heard can come out a cell off, and the robots that fix theirs from it inherit the
    error: six robots round a hole of the noisy star each held a cell one off, counted the
    hole as filled and never carried it out. Asking every neighbour was not enough: on the
    1,018-robot S under noise (seed 1) a block of 196 robots held frames a cell off, each
    outvoted by its own block, and the shape stood at 99.1 % for good, nine robots outside it
    believing they were on it. Nearness to the seeds is counted in hops through robots at
    rest (`anchor`: 1 beside a seed, else one more than the least its neighbours at rest
    say), which no frame error changes; asking only neighbours with fewer hops, corrections
    spread from the seeds outward and an error cannot hold itself up. Where no robot at rest
    is within reach of the seeds (the star's, ring's and horse's stand cells away from the
    shape), no robot has hops to count, and a robot asks all its localised neighbours at rest
    again: asking none, one robot of the noisy star a cell off stood off its shape believing
    it was on it, and the star stood at 99.7 % for good (seed 0). At rest with neighbours at
    rest the reading is exact, so without noise no robot moves its cell.

    Compiled (`_localise`): as a dozen numpy passes over every entry it cost `mean-shift` a
    fifth of its step at 5,000 robots."""
    # not a masked add: numpy 2.4 copies a 2-D array's masked rows one by one, 5 times slower
    memory.frame += np.where(memory.localised[:, None], sense.moved, 0)
    found, memory.anchor = _localise(
        sense.start, sense.offset, sense.progress, sense.heading, sense.seed, sense.seed_frame,
        sense.heard & sense.kin, said.cell, said.heading, said.progress, said.localised,
        said.stays, relay.heard(said.anchor), memory.localised, sense.ready, memory.frame,
    )  # fmt: skip
    memory.localised |= found


def anchor_said(sense: Perception, memory: Memory) -> np.ndarray:
    """The ``anchor`` field a robot broadcasts: its hops to the seeds while it is localised
    and at rest (a robot under way is no fixed point to count through), none otherwise."""
    at_rest = memory.localised & sense.ready
    return relay.said(np.where(at_rest, memory.anchor, relay.NONE), relay.NONE)


@njit
def _localise(
    start: np.ndarray,
    offset: np.ndarray,
    progress: np.ndarray,
    heading: np.ndarray,
    seed: np.ndarray,
    seed_frame: np.ndarray,
    kin: np.ndarray,
    cell: np.ndarray,
    said_heading: np.ndarray,
    said_progress: np.ndarray,
    said_localised: np.ndarray,
    stays: np.ndarray,
    anchor: np.ndarray,
    localised: np.ndarray,
    ready: np.ndarray,
    frame: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover (compiled)
    """`localise` robot by robot over its entries (in reach order): a robot not yet localised
    takes the cell its first usable entry puts it on; a localised one at rest moves its
    `frame` to the cell most of its still entries nearer the seeds put it on, within two
    cells. Returns which robots found their cell, and every robot's hops to the seeds (from
    the `anchor` hops its neighbours said, `relay.NONE` for none)."""
    n = len(start) - 1
    found = np.zeros(n, dtype=np.bool_)
    hops = np.full(n, relay.NONE, dtype=np.int64)
    votes = np.zeros(25, dtype=np.int64)
    for r in range(n):
        for e in range(start[r], start[r + 1]):
            if kin[e] and seed[e]:
                hops[r] = 1
            elif kin[e] and said_localised[e] == 1 and stays[e] == 1 and anchor[e] < hops[r] - 1:
                hops[r] = anchor[e] + 1
        mx, my = progress[r] * STEPS[heading[r], 0], progress[r] * STEPS[heading[r], 1]
        at_rest = localised[r] and ready[r]
        votes[:] = 0
        for e in range(start[r], start[r + 1]):
            if not kin[e]:
                continue
            # beside a seed, the seeds alone; else the still robots nearer the seeds; with no
            # count to the seeds (none at rest within reach of them), every still robot
            still = not seed[e] and said_localised[e] == 1 and stays[e] == 1
            if hops[r] == 1:
                nearer = seed[e]
            else:
                nearer = still and (anchor[e] < hops[r] or hops[r] == relay.NONE)
            if localised[r] and not (at_rest and nearer):
                continue  # it has its cell and this entry has no vote: nothing to work out
            rx, ry, moving = float(cell[e, 0]), float(cell[e, 1]), False
            if said_heading[e] > 0:  # else it is on its cell: s * 0 moves it nowhere
                hx, hy = STEPS[said_heading[e], 0], STEPS[said_heading[e], 1]
                told = said_progress[e] / FIXED
                along = (offset[e, 0] + mx) * hx + (offset[e, 1] + my) * hy
                gone = np.mod(along - told, 1.0)
                s = told + gone
                rx, ry = cell[e, 0] + s * hx, cell[e, 1] + s * hy
                moving = gone > WHOLE and gone < 1 - WHOLE
            if seed[e]:
                rx, ry = float(seed_frame[e, 0]), float(seed_frame[e, 1])
            ex, ey = rx - offset[e, 0] - mx, ry - offset[e, 1] - my
            x, y = np.rint(ex), np.rint(ey)
            if not (abs(ex - x) < WHOLE and abs(ey - y) < WHOLE):
                continue
            robot = not seed[e] and said_localised[e] == 1 and (stays[e] == 1 or moving)
            if not localised[r] and not found[r] and (robot or seed[e]):
                frame[r, 0], frame[r, 1], found[r] = int(x), int(y), True
            if at_rest and nearer:
                dx, dy = int(x) - frame[r, 0], int(y) - frame[r, 1]
                if abs(dx) <= 2 and abs(dy) <= 2:
                    votes[(dx + 2) * 5 + dy + 2] += 1
        if at_rest:
            best = np.argmax(votes)
            if best != 12 and votes[best] > votes[12]:
                frame[r, 0] += best // 5 - 2
                frame[r, 1] += best % 5 - 2
    return found, hops


def find_the_others(
    sense: Perception,
    memory: Memory,
    said: SimpleNamespace,
    view: View,
    turn_every: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of the robots that do not know where they are: toward the nearest seed or
    localised neighbour, stopping beside it to take their bearings; with none in sight,
    `roam`. Robots that do not know where they are tell each other nothing: a count of hops
    passed among them would only count up for ever where no localised robot is."""
    best = known_to(sense, said, np.flatnonzero(~memory.localised))
    lost = ~memory.localised & (best < 0)
    moves = roam(sense, memory.roam, lost, lambda robots, cells: view.at(robots, cells)[0],
                 turn_every, rng)  # fmt: skip
    toward = np.flatnonzero(~memory.localised & sense.ready & (best >= 0))
    offset = sense.offset[best[toward]]
    far = np.abs(offset).max(axis=1) >= 1.5  # not yet beside it: go on
    along_x = np.abs(offset[:, 0]) >= np.abs(offset[:, 1])
    way = np.where(along_x, np.where(offset[:, 0] > 0, 1, 2), np.where(offset[:, 1] > 0, 3, 4))
    moves[toward[far]] = way[far]
    return moves


def roam(
    sense: Perception,
    way: np.ndarray,
    lost: np.ndarray,
    taken: Callable[[np.ndarray, np.ndarray], np.ndarray],
    turn_every: int,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of the `lost` robots (a mask: robots with nothing in sight to head for):
    straight on across the arena at speed, turning wherever blocked and at random with chance
    1/`turn_every` at each step it goes on under way (a cell takes one or two of those): a
    straight walk crosses an arena in its width, a random one needs its area squared. `way`
    is their memory of the way they go (0: none yet); ``taken(robots, offsets)`` says whether
    each of `robots` senses something there."""
    moves = np.zeros(len(sense), dtype=np.int64)
    roaming = np.flatnonzero(lost & sense.ready)
    ways = way[roaming]
    failed = (sense.moved[roaming] == 0).all(axis=1)  # a wall (or a cell taken first)
    blocked = taken(roaming, STEPS[ways]) | (ways == 0) | failed
    # any of the four ways with none yet (or after a stop), else any but the one that failed
    going = ways > 0
    fresh = rng.integers(1, len(STEPS) - going)
    ways = np.where(blocked, fresh + (going & (fresh >= ways)), ways)
    way[roaming] = ways
    moves[roaming] = ways
    # under way, straight on while clear, and now and then a stop, to turn at random after it
    rows = np.flatnonzero(lost & sense.cruising & (sense.heading == way))
    clear = ~taken(rows, 2 * STEPS[sense.heading[rows]])
    keep = clear & (rng.random(len(rows)) >= 1 / turn_every)
    moves[rows[keep]] = sense.heading[rows[keep]]
    way[rows[~keep]] = 0
    return moves


def known_to(sense: Perception, said: SimpleNamespace, robots: np.ndarray) -> np.ndarray:
    """Per robot, the entry of the nearest seed or localised neighbour it hears (-1: none, and
    for robots not among `robots`). Only their entries are looked through: once most robots
    know where they are, a pass over every entry cost a 10,000-robot step 0.3 ms."""
    counts = sense.start[robots + 1] - sense.start[robots]
    entries = np.repeat(sense.start[robots] - np.cumsum(counts) + counts, counts)
    entries += np.arange(len(entries))
    known = sense.heard[entries] & sense.kin[entries]
    known &= sense.seed[entries] | (said.localised[entries] == 1)
    first = relay.best_per_robot(len(sense), sense.owner[entries], np.zeros(len(entries)), known)
    best = np.full(len(sense), -1, dtype=np.int64)
    best[first >= 0] = entries[first[first >= 0]]
    return best

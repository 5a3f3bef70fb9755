"""Working out where a robot is, in its seed frame, from the seeds and its neighbours.

Seeds broadcast their frame cells; a robot that knows its frame cell broadcasts it, the way it
is moving and how far along, and whether it stays there next step. A robot that does not know
where it is takes its cell from the nearest seed or such a neighbour (see `localise`), and from
then on keeps it by odometry. So knowledge spreads outward from the seeds a sensing radius a
step, through robots at rest and on the move. A robot that knows nothing walks toward one that
does, or roams straight across the arena until it sees one.

A program using these keeps memory slots ``localised``, ``frame`` (2) and ``roam``, and
broadcasts fields ``localised``, ``cell`` (2), ``heading`` (the move it is making or starting,
0 if it stays), ``progress`` (in 1/`FIXED` cells) and ``stays``.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

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
    for can fail), so it is used only when it said it stays."""
    memory.frame[memory.localised] += sense.moved[memory.localised]
    owner = sense.owner
    kin = sense.heard & sense.kin
    heading = STEPS[said.heading]
    mine = sense.progress[owner, None] * STEPS[sense.heading[owner]]
    told = said.progress / FIXED
    along = ((sense.offset + mine) * heading).sum(axis=1)
    gone = np.mod(along - told, 1.0)
    s = told + gone
    reference = np.where(sense.seed[:, None], sense.seed_frame, said.cell + s[:, None] * heading)
    estimate = reference - sense.offset - mine
    cells = np.rint(estimate).astype(np.int64)
    whole = (np.abs(estimate - cells) < WHOLE).all(axis=1)
    moving = (said.heading > 0) & (gone > WHOLE) & (gone < 1 - WHOLE)
    robot = kin & ~sense.seed & (said.localised == 1) & ((said.stays == 1) | moving)
    usable = whole & (robot | kin & sense.seed) & ~memory.localised[owner]
    first = relay.best_per_robot(len(sense), owner, np.zeros(len(usable)), usable)
    found = first >= 0
    memory.frame[found] = cells[first[found]]
    _recheck(sense, memory, cells, whole & (kin & sense.seed | robot & (said.stays == 1)))
    memory.localised |= found


def _recheck(sense: Perception, memory: Memory, cells: np.ndarray, still: np.ndarray) -> None:
    """A localised robot at rest takes the cell most of its seeds and localised neighbours at
    rest put it on (`cells`, per entry, where `still`), when more of them say so than say it is
    where it thinks. A fix from a neighbour that turned as it was heard can come out a cell
    off, and the robots that fix theirs from it inherit the error: six robots round a hole of
    the noisy star each held a cell one off, counted the hole as filled and never carried it
    out. At rest with neighbours at rest the reading is exact, so without noise no robot moves
    its cell."""
    owner = sense.owner
    at_rest = memory.localised & sense.ready
    votes = still & at_rest[owner]
    off = cells - memory.frame[owner]
    near = votes & (np.abs(off) <= 2).all(axis=1)
    code = (off[:, 0] + 2) * 5 + off[:, 1] + 2
    counts = np.bincount(owner[near] * 25 + code[near], minlength=len(sense) * 25)
    counts = counts.reshape(len(sense), 25)
    best = counts.argmax(axis=1)
    moves = (best != 12) & (counts[np.arange(len(sense)), best] > counts[:, 12])
    moves &= counts[np.arange(len(sense)), best] >= 2
    memory.frame[moves] += np.stack([best[moves] // 5 - 2, best[moves] % 5 - 2], axis=1)


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
    straight on across the arena at speed, turning at random about every `turn_every` steps
    and wherever blocked (a straight walk crosses an arena in its width, a random one needs
    its area squared). Robots that do not know where they are tell each other nothing: a
    count of hops passed among them would only count up for ever where no localised robot
    is."""
    kin = sense.heard & sense.kin
    known = kin & (sense.seed | (said.localised == 1))
    lost = ~memory.localised & sense.ready
    moves = np.zeros(len(sense), dtype=np.int64)
    best = known_to(sense, known)
    toward = np.flatnonzero(lost & (best >= 0))
    offset = sense.offset[best[toward]]
    far = np.abs(offset).max(axis=1) >= 1.5  # not yet beside it: go on
    along_x = np.abs(offset[:, 0]) >= np.abs(offset[:, 1])
    way = np.where(along_x, np.where(offset[:, 0] > 0, 1, 2), np.where(offset[:, 1] > 0, 3, 4))
    moves[toward[far]] = way[far]
    roaming = np.flatnonzero(lost & (best < 0))
    way = memory.roam[roaming]
    failed = (sense.moved[roaming] == 0).all(axis=1)  # a wall (or a cell taken first)
    blocked = view.at(roaming, STEPS[way])[0] | (way == 0) | failed
    fresh = rng.integers(1, len(STEPS) - 1, len(roaming))  # any way but the one that failed
    way = np.where(blocked, np.where(fresh >= way, fresh + 1, fresh), way)
    memory.roam[roaming] = way
    moves[roaming] = way
    # under way, straight on while clear, and now and then a stop, to turn at random after it
    going = ~memory.localised & sense.cruising & (sense.heading == memory.roam)
    going &= ~(known_to(sense, known) >= 0)
    rows = np.flatnonzero(going)
    clear = ~view.at(rows, 2 * STEPS[sense.heading[rows]])[0]
    keep = clear & (rng.random(len(rows)) >= 1 / turn_every)
    moves[rows[keep]] = sense.heading[rows[keep]]
    memory.roam[rows[~keep]] = 0
    return moves


def known_to(sense: Perception, known: np.ndarray) -> np.ndarray:
    """Per robot, the entry of the nearest seed or localised neighbour it hears (-1: none)."""
    return relay.best_per_robot(len(sense), sense.owner, np.zeros(len(known)), known)

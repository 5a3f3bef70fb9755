"""`local-swap`: local task swapping (Wang and Rubenstein, "Shape formation in homogeneous swarms
using local task swapping", IEEE Transactions on Robotics 36(3), 2020).

No global matching and no global queue: robot number k of a group starts with the shape's k-th
cell as its goal (robots numbered past the shape's size are spare), works out where it is from
the seeds and localised neighbours, and walks greedily toward its goal. Neighbours within
range trade goals whenever that shortens their summed distance, or when one is blocked by the
other resting on its goal (the trade then sends both on). A trade needs both sides: each robot
broadcasts the neighbour it wants to trade with, and two robots that want each other trade in
the same step, from the same two messages, so a goal is never lost or held twice.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from swarmshape.core.local import Memory, Program, Slot
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Perception
from swarmshape.strategies import register

LOCALISED, X, Y, GOAL, WANTS, NUMBER, STAYS, HOPS = range(8)
"""What a robot broadcasts, in order. STAYS: it was at rest and asked for no move, so next step
it is still on the cell (X, Y) it names, and a neighbour may take its bearings from it. HOPS:
hops to the nearest localised robot (0 if localised), a gradient the lost ones climb down."""

FAR = 1000
"""HOPS of a robot that hears of no localised robot at all."""

PATIENCE = 4
"""Steps a robot waits behind something before it goes round it (see `_go_round`)."""

REVERSE = np.array([0, 2, 1, 4, 3])
"""The opposite of each direction index."""

UNSET = -2
"""A goal not yet drawn from the robot's number (the first step)."""


@register
class LocalSwap(Program):
    name = "local-swap"
    description = "goals by robot number, traded between neighbours (Wang & Rubenstein 2020)"
    message_size = 8
    memory: ClassVar[dict[str, Slot]] = {
        "localised": Slot(bool, False),
        "frame": Slot(np.int64, 0, 2),
        "goal": Slot(np.int64, UNSET),
        "wants": Slot(np.int64, -1),
        "waited": Slot(np.int64, 0),
        "blocked_way": Slot(np.int64, 0),
        "detour": Slot(np.int64, 0),
        "at_goal": Slot(bool, False),
        "asked": Slot(np.int64, 0),
        "roam": Slot(np.int64, 0),
    }

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        localise(sense, memory)
        count = sense.blueprint.count(sense.group)
        unset = memory.goal == UNSET
        memory.goal[unset] = np.where(sense.number < count, sense.number, -1)[unset]
        memory.goal[memory.goal >= count] = -1
        _trade(sense, memory)
        goal_cell = _goal_cells(sense, memory.goal)
        has_goal = memory.localised & (memory.goal >= 0)
        memory.at_goal = has_goal & (memory.frame == goal_cell).all(axis=1)
        occupied = _occupied(sense)
        _note_walls(sense, memory, occupied)
        going = has_goal & ~memory.at_goal
        preferred, first = _preferred(goal_cell - memory.frame, occupied, going)
        memory.wants = _choose_partner(sense, memory, goal_cell, preferred)
        moves = _go_round(memory, preferred, first, occupied, going & sense.ready, rng)
        moves[memory.wants >= 0] = 0  # hold still while a trade is agreed
        spare_in_shape = (memory.goal < 0) & sense.blueprint.contains(sense.group, memory.frame)
        hops, toward = _hops(sense, memory)
        lost = ~memory.localised
        moves[lost] = np.where(occupied[lost, toward[lost]], 0, toward[lost])
        roaming = lost & (hops >= FAR)
        moves[roaming] = _roam(memory, occupied, roaming, rng)
        wander = lost & ~roaming & (moves == 0) & (rng.random(len(sense)) < 0.5)
        wander |= spare_in_shape & memory.localised & (rng.random(len(sense)) < 0.1)
        moves[wander] = _random_free(occupied[wander], rng)
        memory.asked = np.where(sense.ready, moves, 0)
        stays = sense.ready & (moves == 0)
        messages = np.column_stack(
            [memory.localised, memory.frame, memory.goal, memory.wants, sense.number, stays, hops]
        ).astype(np.int64)
        return moves, messages

    def finished(self, memory: Memory) -> np.ndarray:
        return memory.at_goal

    def estimate(self, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
        return memory.localised, memory.frame


def localise(sense: Perception, memory: Memory) -> None:
    """Dead-reckon localised robots by their odometry; a robot at rest that is not localised
    takes its frame cell from its nearest seed or localised neighbour (that one's frame cell
    less the sensed offset), when the offset reads as whole cells."""
    memory.frame[memory.localised] += sense.moved[memory.localised]
    cells = np.rint(sense.offset).astype(np.int64)
    whole = (np.abs(sense.offset - cells) < 0.25).all(axis=1)
    robot = sense.heard & sense.kin & ~sense.seed & (sense.message[:, LOCALISED] == 1)
    robot &= sense.message[:, STAYS] == 1
    reference = np.where(sense.seed[:, None], sense.seed_frame, sense.message[:, X : Y + 1])
    usable = whole & (robot | sense.heard & sense.kin & sense.seed)
    usable &= ~memory.localised[sense.owner] & sense.ready[sense.owner]
    first = _first_per_robot(usable, sense)
    found = first >= 0
    memory.frame[found] = (reference - cells)[first[found]]
    memory.localised |= found


def _hops(sense: Perception, memory: Memory) -> tuple[np.ndarray, np.ndarray]:
    """Each robot's hops to a localised robot (a seed counts), and the direction of its
    neighbour nearest one (0 if none is nearer than itself)."""
    heard_hops = np.where(
        sense.seed, 0, np.where(sense.kin & ~sense.seed, sense.message[:, HOPS], FAR)
    )
    heard_hops = np.where(sense.heard & sense.kin, heard_hops, FAR)
    heard_hops[~sense.seed & (sense.message[:, LOCALISED] == 0) & (heard_hops == 0)] = FAR
    order = np.lexsort((heard_hops, sense.owner))
    best = np.full(len(sense), -1, dtype=np.int64)
    owners = sense.owner[order]
    firsts = order[np.r_[True, owners[1:] != owners[:-1]]] if len(order) else order
    best[sense.owner[firsts]] = firsts
    found = best >= 0
    nearest = np.full(len(sense), FAR, dtype=np.int64)
    nearest[found] = heard_hops[best[found]]
    hops = np.where(memory.localised, 0, np.minimum(nearest + 1, FAR))
    offset = np.zeros((len(sense), 2))
    offset[found] = sense.offset[best[found]]
    along_x = np.abs(offset[:, 0]) >= np.abs(offset[:, 1])
    way = np.where(along_x, np.where(offset[:, 0] > 0, 1, 2), np.where(offset[:, 1] > 0, 3, 4))
    closer = found & (nearest < FAR) & (np.abs(offset).max(axis=1) >= 1.5)
    return hops, np.where(closer, way, 0)


def _first_per_robot(mask: np.ndarray, sense: Perception) -> np.ndarray:
    """Per robot, the index of its first entry (nearest, as sensed in reach order) in `mask`,
    or -1."""
    first = np.full(len(sense), -1, dtype=np.int64)
    entries = np.flatnonzero(mask)[::-1]  # written last to first, so the first entry stays
    first[sense.owner[entries]] = entries
    return first


def _goal_cells(sense: Perception, goal: np.ndarray) -> np.ndarray:
    return sense.blueprint.cell(sense.group, np.maximum(goal, 0))


def _occupied(sense: Perception) -> np.ndarray:
    """``(n, 5)``: whether something sits in the cell one step in each direction."""
    cells = np.rint(sense.offset).astype(np.int64)
    occupied = np.zeros((len(sense), len(STEPS)), dtype=bool)
    for direction in range(1, len(STEPS)):
        near = (np.abs(sense.offset - STEPS[direction]) < 0.75).all(axis=1)
        hit = near & (cells == STEPS[direction]).all(axis=1)
        occupied[sense.owner[hit], direction] = True
    return occupied


def _note_walls(sense: Perception, memory: Memory, occupied: np.ndarray) -> None:
    """A move asked for last step that did not happen met something a robot cannot sense (the
    arena's edge, or a cell another robot took first): treat that way as blocked now, so a
    detour turns back at a wall instead of pushing into it for ever."""
    failed = np.flatnonzero(sense.ready & (memory.asked > 0) & (sense.moved == 0).all(axis=1))
    occupied[failed, memory.asked[failed]] = True


def _preferred(
    delta: np.ndarray, occupied: np.ndarray, going: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """A free direction toward the goal, the longer way first, or 0 (none, or not going); and
    the first choice, free or not."""
    x = np.where(delta[:, 0] > 0, 1, np.where(delta[:, 0] < 0, 2, 0))
    y = np.where(delta[:, 1] > 0, 3, np.where(delta[:, 1] < 0, 4, 0))
    longer_x = np.abs(delta[:, 0]) >= np.abs(delta[:, 1])
    first, second = np.where(longer_x, x, y), np.where(longer_x, y, x)
    rows = np.arange(len(delta))
    chosen = np.where(~occupied[rows, first], first, np.where(~occupied[rows, second], second, 0))
    return np.where(going, chosen, 0), first


def _go_round(
    memory: Memory,
    preferred: np.ndarray,
    first: np.ndarray,
    occupied: np.ndarray,
    ready: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """Moves of robots on their way, going round what blocks them like a bug algorithm: after
    `PATIENCE` steps blocked, a robot steps sideways (a random side) and keeps that way until
    the way it was blocked in is free, turning back when the side is blocked too."""
    rows = np.arange(len(first))
    blocked = ready & (preferred == 0) & (first > 0)
    memory.waited = np.where(blocked & (memory.detour == 0), memory.waited + 1, 0)
    start = blocked & (memory.waited > PATIENCE)
    sideways = np.where(first <= 2, 3, 1) + (rng.random(len(first)) < 0.5)
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
    sense: Perception, memory: Memory, goal_cell: np.ndarray, preferred: np.ndarray
) -> np.ndarray:
    """The neighbour each robot wants to trade goals with next step (its number), or -1."""
    me, msg = sense.owner, sense.message
    talk = sense.heard & sense.kin & ~sense.seed & (msg[:, LOCALISED] == 1)
    talk &= memory.localised[me] & sense.ready[me] & (msg[:, STAYS] == 1)
    their_goal = msg[:, GOAL]
    their_cell = _goal_cells_of(sense, me, their_goal)
    mine, theirs = memory.frame[me], msg[:, X : Y + 1]

    def apart(where: np.ndarray, goal_at: np.ndarray, goal: np.ndarray) -> np.ndarray:
        return np.where(goal >= 0, np.abs(where - goal_at).sum(axis=1), 0)

    now = apart(mine, goal_cell[me], memory.goal[me]) + apart(theirs, their_cell, their_goal)
    traded = apart(mine, their_cell, their_goal) + apart(theirs, goal_cell[me], memory.goal[me])
    gain = now - traded
    asked = msg[:, WANTS] == sense.number[me]
    toward = goal_cell[me] - mine
    blocked = (memory.goal[me] >= 0) & (preferred[me] == 0) & (np.abs(toward).sum(axis=1) > 0)
    resting_there = (theirs == their_cell).all(axis=1) & (their_goal >= 0)
    in_the_way = blocked & resting_there & (np.abs(theirs - mine).sum(axis=1) == 1)
    in_the_way &= (np.sign(theirs - mine) * np.sign(toward) > 0).any(axis=1)
    score = np.where(gain > 0, 2 * gain + asked, np.where((gain == 0) & (asked | in_the_way), 1, 0))
    score = np.where(talk & (memory.goal[me] != their_goal), score, 0)
    best = np.full(len(sense), -1, dtype=np.int64)
    order = np.lexsort((-score, me))
    candidates = order[score[order] > 0]
    owners = me[candidates]
    firsts = candidates[np.r_[True, owners[1:] != owners[:-1]]] if len(candidates) else candidates
    best[me[firsts]] = msg[firsts, NUMBER]
    return best


def _goal_cells_of(sense: Perception, me: np.ndarray, goal: np.ndarray) -> np.ndarray:
    count = sense.blueprint.count(sense.group[me])
    return sense.blueprint.cell(sense.group[me], np.clip(goal, 0, count - 1))


def _trade(sense: Perception, memory: Memory) -> None:
    """Robots that wanted each other last step, and hear each other now, swap goals."""
    me, msg = sense.owner, sense.message
    mutual = sense.heard & sense.kin & ~sense.seed & (memory.wants[me] >= 0)
    mutual &= (msg[:, NUMBER] == memory.wants[me]) & (msg[:, WANTS] == sense.number[me])
    memory.goal[me[mutual]] = msg[mutual, GOAL]


def _roam(
    memory: Memory, occupied: np.ndarray, roaming: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Moves of robots that hear of no localised robot: straight on until blocked (a wall
    shows as a move that failed), then a new random way. A straight walk crosses the arena in
    its width; a random walk needs its area squared, which left small swarms in big arenas
    searching for tens of thousands of steps."""
    rows = np.flatnonzero(roaming)
    way = memory.roam[rows]
    turn = (way == 0) | occupied[rows, way] | (rng.random(len(rows)) < 0.02)
    way[turn] = _random_free(occupied[rows[turn]], rng)
    memory.roam[rows] = way
    return way


def _random_free(occupied: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random direction whose cell is free for each robot, or 0 if none is."""
    noise = rng.random(occupied.shape)
    noise[:, 0] = -1.0
    noise[occupied] = -1.0
    choice = noise.argmax(axis=1)
    return np.where(noise.max(axis=1) > 0, choice, 0)

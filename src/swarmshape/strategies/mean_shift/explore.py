"""The paper's two commands that steer a robot toward its shape, on the lattice.

- **Entering** (Sun et al.'s shape-entering command): a robot outside its shape heads down
  its grey level ``xi``, the fewest moves to the shape round the seeds (the paper's grey image:
  black on the shape, white beyond a band of grey round it; a robot on a grey cell heads for a
  lower grey cell), with a weight that falls as it nears the shape: ``k1 * min(xi / band, 1)``.
  The way to the *nearest* shape cell would do but for the seeds: a robot beyond them, their
  far side facing the shape, pushed against them for ever.
- **Exploration** (the mean shift): the weighted mean of the offsets of the unoccupied shape
  cells a robot senses, ``k2 * sum(psi * o) / sum(psi)``, with the raised-cosine kernel
  ``psi(z) = (1 + cos(pi z)) / 2`` of the distance over the sensing radius plus one (so that
  every sensed cell weighs something, as the paper's kernel reaches a little past its sensing
  radius). A cell is unoccupied if nothing the robot senses stands on it; the robot's own cell
  is not counted, or a lone hole beside a robot would weigh against its own cell and never
  draw it.

Both are worked out from a robot's *base*: its cell at rest, or, under way, the cell it is
coming to, which is where a move it asks for now would start (see `base`).
"""

from __future__ import annotations

import functools

import numpy as np
import scipy

from swarmshape.core.compiled import njit
from swarmshape.core.local import Memory
from swarmshape.core.motion import LEFT, REVERSE, RIGHT, STEPS
from swarmshape.core.perception import Blueprint, Perception
from swarmshape.core.shape import SEED_CELLS
from swarmshape.strategies import routes
from swarmshape.strategies.skills.shape import Around
from swarmshape.strategies.skills.view import View, distances


def base(sense: Perception) -> np.ndarray:
    """Each robot's base relative to its own cell ``(n, 2)``: its next cell when it is under
    way with only that one reserved (it may go on from there), else its own cell."""
    return np.where(sense.cruising[:, None], np.take(STEPS, sense.heading, axis=0), 0)


class Window:
    """The cells within the sensing radius of a robot's own cell, as offsets ``(k, 2)`` (its
    own cell among them: under way, it is the cell it leaves) and the kernel that weighs them."""

    def __init__(self, radius: float) -> None:
        r = int(radius)
        grid = np.mgrid[-r : r + 1, -r : r + 1].reshape(2, -1).T
        self.offsets = grid[np.hypot(*grid.T) <= radius]
        self.radius = radius
        # a base is the robot's own cell or one beside it (`base`): the kernel from each of the
        # nine cells round its own, worked out here, not for every robot
        relative = self.offsets[None, None] - np.mgrid[-1:2, -1:2].transpose(1, 2, 0)[:, :, None]
        z = np.minimum(np.hypot(relative[..., 0], relative[..., 1]) / (radius + 1), 1.0)
        self._kernels = (1 + np.cos(np.pi * z)) / 2

    def weights(self, base: np.ndarray) -> np.ndarray:
        """Per robot, the kernel over the window's `offsets` ``(n, k)`` from its `base`
        ``(n, 2)``: 1 at the base, 0 one cell past the sensing radius."""
        nine = self._kernels.reshape(9, -1)  # np.take: see `mean_shift`
        return np.take(nine, (base[:, 0] + 1) * 3 + base[:, 1] + 1, axis=0)


@functools.lru_cache(maxsize=4)
def window(radius: float) -> Window:
    """The `Window` of a sensing radius, worked out once: each step it took 0.15 ms."""
    return Window(radius)


def mean_shift(
    sense: Perception,
    around: Around,
    view: View,
    window: Window,
    base: np.ndarray,
    outside: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Per robot, the mean shift from its base toward the unoccupied shape cells it senses
    ``(n, 2)`` (in cells; zero when it senses none), and which cells of the window those are
    ``(n, k)`` (its base never among them). A robot `outside` its shape counts only the cells
    it can walk to through free cells it senses: it cannot pass the robots in place, and
    cells beyond them come out to it as holes (`holes`).

    Rows are gathered by `np.take`: numpy 2.4's ``array[rows]`` of an array of two or more
    axes copies row by row, 7 to 14 times slower."""
    n, offsets = len(sense), window.offsets
    r = view.reach
    free = np.empty((n, len(offsets)), dtype=bool)
    _unoccupied(view.bordered_taken, r, around.inside, around.reach, offsets, base, free)
    rows = np.flatnonzero(outside & any_per_row(free))  # the others have no cell to reach
    walls, side = view.taken_of(rows), 2 * r + 1
    reach = walkable(walls, np.take(base, rows, axis=0), offsets).reshape(len(rows), side * side)
    free[rows] &= np.take(reach, (offsets[:, 0] + r) * side + offsets[:, 1] + r, axis=1)
    rows = np.flatnonzero(any_per_row(free))  # for the others the shift is zero
    weight = np.where(np.take(free, rows, axis=0), window.weights(np.take(base, rows, axis=0)), 0.0)
    total = weight.sum(axis=1)
    sees = total > 0
    rows, weight, total = rows[sees], weight[sees], total[sees]
    shift = np.zeros((n, 2))
    relative = offsets[None] - np.take(base, rows, axis=0)[:, None, :]
    shift[rows] = np.einsum("nk,nkd->nd", weight, relative) / total[:, None]
    return shift, free


@njit
def _unoccupied(
    taken: np.ndarray,
    sight: int,
    inside: np.ndarray,
    reach: int,
    offsets: np.ndarray,
    base: np.ndarray,
    free: np.ndarray,
) -> None:  # pragma: no cover (compiled)
    """`mean_shift`'s unoccupied shape cells, per robot and window offset: in its shape
    (`Around`'s squares, `reach` cells either way), nothing it senses on it (`View`'s bordered
    squares, `sight` cells either way) and not its `base`. Three numpy passes over every
    robot's window cost 0.85 ms a step at 10,000 robots."""
    for robot in range(len(base)):
        for j in range(len(offsets)):
            x, y = offsets[j, 0], offsets[j, 1]
            free[robot, j] = (
                inside[robot, x + reach, y + reach]
                and not taken[robot, x + sight + 1, y + sight + 1]
                and (x != base[robot, 0] or y != base[robot, 1])
            )


def any_per_row(mask: np.ndarray) -> np.ndarray:
    """``mask.any(axis=1)`` of a 2-D mask: numpy sets its reduction up row by row, 0.15 ms
    over 10,000 robots' four moves, and `mean-shift` asks a dozen times a step."""
    out = np.empty(len(mask), dtype=bool)
    _any_per_row(mask, out)
    return out


@njit
def _any_per_row(mask: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover (compiled)
    for row in range(mask.shape[0]):
        out[row] = False
        for column in range(mask.shape[1]):
            if mask[row, column]:
                out[row] = True
                break


def walkable(walls: np.ndarray, base: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The cells of each robot's view square ``(k, side, side)`` it can walk to from its base
    round `walls` (its view square) through cells it senses (its window's `offsets`), four
    ways."""
    r = walls.shape[1] // 2
    start = np.zeros_like(walls)
    start[np.arange(len(walls)), base[:, 0] + r, base[:, 1] + r] = True
    return distances(walls | ~sensed(offsets, r), start) >= 0


def sensed(offsets: np.ndarray, reach: int) -> np.ndarray:
    """The window's `offsets` as a mask of a view square of half-width `reach`. The square's
    corners lie beyond the sensing radius, where a robot sees nothing, taken or not: counted
    free, they made ways round robots in place that were not there, and a robot above the
    S's middle bar walked to and fro for good toward a hole below it (the S at 14 cells,
    seed 0)."""
    mask = np.zeros((2 * reach + 1, 2 * reach + 1), dtype=bool)
    mask[offsets[:, 0] + reach, offsets[:, 1] + reach] = True
    return mask


def seeded(taken: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Robots' view squares `taken` ``(k, side, side)`` with the seeds marked too, where each
    robot's frame cell `frame` ``(k, 2)`` puts them: every robot knows where they stand, sensed
    or not."""
    r = taken.shape[1] // 2
    marked = taken.copy()
    for seed in SEED_CELLS:
        at = seed - frame + r
        near = ((at >= 0) & (at <= 2 * r)).all(axis=1)
        marked[np.flatnonzero(near), at[near, 0], at[near, 1]] = True
    return marked


def nearer(
    taken: np.ndarray, base: np.ndarray, free: np.ndarray, offsets: np.ndarray
) -> np.ndarray:
    """``(n, 4)``: for each robot, the moves from its base that bring it a cell nearer, through
    cells it senses (`sensed`) not `taken` (its `View` square, `seeded`: a seed beyond its
    senses, taken for free, opened a way round the seeds that it shut again a step later, and
    two robots swapped places for ever), to the nearest of its `free` cells ``(n, k)`` at
    window `offsets` (none when it can reach none). A robot outside its shape takes one of
    these, so each of its moves brings it nearer an empty cell: straight toward the mean of
    the cells, round a robot standing still (stalled, say), it would step aside and back for
    ever."""
    n, r = len(base), taken.shape[1] // 2
    passable = ~taken & sensed(offsets, r)
    goal = np.zeros_like(passable)
    goal[:, offsets[:, 0] + r, offsets[:, 1] + r] = free
    far = np.prod(passable.shape[1:])
    steps = distances(~passable, goal)
    distance = np.where(steps >= 0, steps, far)
    rows = np.arange(n)
    here = distance[rows, base[:, 0] + r, base[:, 1] + r]
    steps = []
    for step in STEPS[1:]:
        x, y = (base + step + r).T
        inside = (x >= 0) & (x <= 2 * r) & (y >= 0) & (y <= 2 * r)
        there = distance[rows, np.clip(x, 0, 2 * r), np.clip(y, 0, 2 * r)]
        steps.append(inside & (there < np.minimum(here, far)))
    return np.stack(steps, axis=1)


def square(reach: int) -> np.ndarray:
    """The offsets of a square of half-width `reach`, row by row ``(1, side * side, 2)``: a
    view square's cells, to look up for every robot at once."""
    span = np.arange(-reach, reach + 1)
    return np.stack(np.meshgrid(span, span, indexing="ij"), axis=-1).reshape(1, -1, 2)


def round_the_silent(
    sense: Perception,
    memory: Memory,
    view: View,
    around: Around,
    window: Window,
    robots: np.ndarray,
    way: np.ndarray,
    target: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """``(k, 4)``: for `robots` following a route round the shape to `target` ``(k, 2)``, the
    moves that bring each nearer its next waypoint `way` round the robots it does not hear
    (stalled ones never make way, and a robot whose straight way one blocked waited behind it
    for good) and the seeds, none when the waypoint lies beyond its window (under way, a
    window ahead of the cell it is coming to); robots that talk are left to make way.

    Where silent robots wall the waypoint off from a robot (with the seeds and the robots on
    the shape, which never make way for it either), and while it goes round a wall, the
    moves toward the cells it can walk to that lie least far along the route
    (`routes.costs`); with none nearer than its base, it goes round what walls it in
    (`go_round`). Aiming at the waypoint still, a robot in a bay of stalled robots stepped
    aside and back for good (`fuzz_programs.py mean-shift`, case 5)."""
    frame = memory.frame[robots]
    # per entry, and not silent for none (a `who` of -1 picks the last): with no entry at
    # all (faults left a robot alone) there is nothing else to pick
    silent = np.append(~sense.heard & ~sense.seed, False)[view.who_of(robots)]
    walls = seeded(silent, frame)
    start, r, offsets = base(sense)[robots], view.reach, window.offsets
    aim = way - frame
    goal = (offsets[None, :, 0] == aim[:, None, 0]) & (offsets[None, :, 1] == aim[:, None, 1])
    moves = nearer(walls, start, goal, offsets)
    # only silent robots in sight, or a wall being gone round, can call for more
    rows = np.flatnonzero(silent.any(axis=(1, 2)) | (memory.rounding[robots] != 0))
    if not len(rows):
        return moves
    side = 2 * r + 1
    on_shape = around.contains(square(r))[robots[rows]].reshape(-1, side, side)
    held = seeded(view.taken_of(robots[rows]) & on_shape, frame[rows])
    firm = held | silent[rows]
    reached = walkable(firm, start[rows], offsets)[:, offsets[:, 0] + r, offsets[:, 1] + r]
    open_way = (goal[rows] & reached).any(axis=1)
    round_held = walkable(held, start[rows], offsets)[:, offsets[:, 0] + r, offsets[:, 1] + r]
    walled = ~open_way & (goal[rows] & round_held).any(axis=1)
    keep = walled | (memory.rounding[robots[rows]] != 0)
    rows, firm, reached = rows[keep], firm[keep], reached[keep]
    if not len(rows):
        return moves
    blueprint, group = sense.blueprint, sense.group[robots[rows]]
    cells = frame[rows, None] + offsets[None]
    cost = np.where(reached, routes.costs(blueprint, group, cells, target[rows]), np.inf)
    here = routes.costs(blueprint, group, (frame + start)[rows, None], target[rows])[:, 0]
    best = cost.min(axis=1, initial=np.inf)
    nearest = (cost == best[:, None]) & (best < here)[:, None]
    moves[rows] = nearer(firm, start[rows], nearest, offsets)
    passable = ~firm & sensed(offsets, r)
    move = go_round(memory, robots[rows], passable, start[rows], way[rows], target[rows],
                    here, best, rng)  # fmt: skip
    rounding = rows[move > 0]
    moves[rounding] = False
    moves[rounding, move[move > 0] - 1] = True
    return moves


def go_round(
    memory: Memory,
    robots: np.ndarray,
    passable: np.ndarray,
    start: np.ndarray,
    way: np.ndarray,
    target: np.ndarray,
    here: np.ndarray,
    best: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """``(k,)``: the move of each of `robots` that goes round what walls it in, 0 for those
    that need not (a bug algorithm: V. Lumelsky and A. Stepanov, "Path-planning strategies
    for a point mobile automaton moving amidst unknown obstacles of arbitrary shape",
    Algorithmica 2:403-430, 1987). A robot none of whose cells it can walk to (`best`, the
    least cost along the route to its `target`) lies nearer than its base (cost `here`)
    notes that cost, picks a hand at random, and turns to face its waypoint `way` if that
    cell is free, else so that what is ahead lies on that hand. While any of the eight cells
    round its base is one it cannot pass (its `passable` view square, from its base
    `start`), it turns toward that hand where it can (round a corner), else goes on, else
    turns away, else back; until it can walk to a cell nearer than the cost it noted. Between
    walls it heads for the least cost it can walk to, which can lead it to and fro between
    two cells, each seeing the least the other way (a review's test on random bays; heading
    only for costs below all before broke fuzz cases that form now, so it is left so)."""
    mine = memory.rounding[robots]
    mine[(memory.round_to[robots] != target).any(axis=1)] = 0
    mine[best < np.where(mine != 0, memory.hit[robots], here)] = 0
    begin = np.flatnonzero((mine == 0) & (best >= here) & np.isfinite(here))
    hand = rng.choice(np.array([1, -1]), size=len(begin))
    mine[begin] = hand
    memory.hit[robots[begin]] = here[begin]
    memory.round_to[robots[begin]] = target[begin]
    toward = way[begin] - memory.frame[robots[begin]] - start[begin]
    ahead = np.where(
        np.abs(toward[:, 0]) >= np.abs(toward[:, 1]),
        np.where(toward[:, 0] >= 0, 1, 2),
        np.where(toward[:, 1] >= 0, 3, 4),
    )
    turned = np.where(hand > 0, RIGHT[ahead], LEFT[ahead])  # what is ahead now on the hand
    memory.facing[robots[begin]] = np.where(_free(passable, begin, start, ahead), ahead, turned)
    memory.rounding[robots] = mine
    going = np.flatnonzero(mine != 0)
    facing = memory.facing[robots[going]]
    turn_in = np.where(mine[going] > 0, LEFT[facing], RIGHT[facing])
    near = np.zeros(len(going), dtype=bool)
    for step in ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)):
        seen, free = _look(passable, going, start, np.array(step))
        near |= seen & ~free
    move = np.zeros(len(robots), dtype=np.int64)
    chosen = np.zeros(len(going), dtype=np.int64)
    options = (REVERSE[turn_in], facing, turn_in)  # least wanted first: the last free wins
    for option, allowed in zip(options, (True, True, near), strict=True):
        chosen = np.where(_free(passable, going, start, option) & allowed, option, chosen)
    back = (chosen == 0) & _free(passable, going, start, REVERSE[facing])
    move[going] = np.where(back, REVERSE[facing], chosen)
    return move


def _free(passable: np.ndarray, rows: np.ndarray, start: np.ndarray, way: np.ndarray) -> np.ndarray:
    """Whether the cell a move `way` from each robot's base `start` is `passable` (rows of its
    view squares)."""
    return _look(passable, rows, start, STEPS[way])[1]


def _look(
    passable: np.ndarray, rows: np.ndarray, start: np.ndarray, step: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Whether the cell `step` from each robot's base `start` lies in its view square, and
    whether it is `passable` (and in it)."""
    r = passable.shape[1] // 2
    x, y = (start[rows] + step + r).T
    inside = (x >= 0) & (x <= 2 * r) & (y >= 0) & (y <= 2 * r)
    return inside, inside & passable[rows, np.clip(x, 0, 2 * r), np.clip(y, 0, 2 * r)]


def entering(
    blueprint: Blueprint, groups: np.ndarray, cells: np.ndarray, band: float
) -> np.ndarray:
    """Per robot of `groups` on frame cell `cells`, its entering command ``(n, 2)``: the unit
    vector along the moves that lower its grey level (one step nearer the shape), times
    ``min(xi / band, 1)`` (zero on the shape). On a ridge, where the way round the seeds is as
    short one way as the opposite way, the two cancel; the robot takes the first of them by
    direction number, or it stood there for good (a 12-cell shape, the robot right above the
    seeds, 92 % for 20,000 steps: ``swarmshape check mean-shift --seed 100``)."""
    xi = grey(blueprint, groups, cells[:, None] + STEPS)  # its cell, each move's
    down = np.empty((len(xi), 2))
    _downhill(xi, down)
    return unit(down) * np.minimum(xi[:, 0] / band, 1.0)[:, None]


@njit
def _downhill(xi: np.ndarray, down: np.ndarray) -> None:  # pragma: no cover (compiled)
    """`entering`'s way per robot, from the levels `xi` of its cell and each move's cell:
    the sum of the moves that lower its level, or the first of them where that sum is zero.
    Five numpy passes over every robot cost a 10,000-robot step 0.6 ms."""
    for robot in range(len(xi)):
        dx = dy = first = 0
        for direction in range(1, len(STEPS)):
            if xi[robot, direction] < xi[robot, 0]:
                dx, dy = dx + STEPS[direction, 0], dy + STEPS[direction, 1]
                first = direction if first == 0 else first
        if dx == 0 and dy == 0:
            dx, dy = STEPS[first, 0], STEPS[first, 1]
        down[robot, 0], down[robot, 1] = dx, dy


def grey(blueprint: Blueprint, groups: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Each frame cell's grey level ``xi``: the fewest moves from it to a cell of its group's
    shape, round the seeds (0 on the shape; the paper's grey image, one level a cell). Per
    robot, one cell ``(n, 2)`` or several ``(n, k, 2)``."""
    xi = np.zeros(cells.shape[:-1], dtype=np.int64)
    per_robot = int(np.prod(cells.shape[1:-1]))  # not -1: numpy cannot tell it for no robot
    flat = cells.reshape(len(cells), per_robot, 2)
    for group, (low, field) in enumerate(_grey_fields(blueprint)):
        mine = np.flatnonzero(groups == group)
        _levels(field, low, flat, mine, xi.reshape(len(cells), per_robot))
    return xi


@njit
def _levels(
    field: np.ndarray, low: np.ndarray, cells: np.ndarray, rows: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover (compiled)
    """`grey` of the robots `rows` of one group, cell by cell: a cell off the field's box is its
    nearest box cell's level plus the way to it. numpy's clip, gather and sums over a
    10,000-robot swarm, five times a step, cost `mean-shift` a tenth of its step."""
    top_x, top_y = field.shape[0] - 1, field.shape[1] - 1
    for i in rows:
        for j in range(cells.shape[1]):
            x, y = cells[i, j, 0] - low[0], cells[i, j, 1] - low[1]
            at_x, at_y = min(max(x, 0), top_x), min(max(y, 0), top_y)
            out[i, j] = field[at_x, at_y] + abs(x - at_x) + abs(y - at_y)


@functools.lru_cache(maxsize=4)
def _grey_fields(blueprint: Blueprint) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Per group, the low corner of its box (shape and seeds with one free cell round them, so
    the way round the seeds never leaves it; a cell off it is its clipped cell's level plus the
    way to it) and the grey level of every cell of the box, found breadth first."""
    fields = []
    for shape in blueprint.cells:
        cells = np.concatenate([shape, SEED_CELLS])
        low = cells.min(axis=0) - 1
        size = tuple(cells.max(axis=0) + 2 - low)
        seeds = np.zeros(size, dtype=bool)
        seeds[SEED_CELLS[:, 0] - low[0], SEED_CELLS[:, 1] - low[1]] = True
        level = np.full(size, np.prod(size), dtype=np.int64)  # past any way round
        front = np.zeros(size, dtype=bool)
        front[shape[:, 0] - low[0], shape[:, 1] - low[1]] = True
        reached, distance = front.copy(), 0
        while front.any():
            level[front] = distance
            grown = scipy.ndimage.binary_dilation(front) & ~reached & ~seeds
            reached |= grown
            front, distance = grown, distance + 1
        fields.append((low, level))
    return tuple(fields)


def unit(vectors: np.ndarray) -> np.ndarray:
    """Vectors ``(n, 2)`` scaled to length 1 (zero stays zero)."""
    vectors = vectors.astype(np.float64)
    length = np.hypot(*vectors.T)[:, None]
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)

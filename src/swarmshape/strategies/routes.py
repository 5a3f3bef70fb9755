"""Shortest ways round a shape, as a robot that knows the shape's bitmap can work them out.

A local program plans over the few cells its robot senses, and a formed shape is an obstacle
far wider than that: a robot on the wrong side of an arm, whose target faces the shape's bay,
walked back and forth along the arm for a thousand steps. Every robot knows the bitmap and
the seeds in its frame, so it can find the way round them alone: the path to its target that
crosses the fewest shape cells (formed ones let a robot through only by trading), and of
those the shortest. Robots in the way are left to the local planner.
"""

from __future__ import annotations

import functools
import itertools
import mmap
from collections.abc import Iterator

import numpy as np
import scipy

from swarmshape.core.compiled import njit
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Blueprint
from swarmshape.core.shape import SEED_CELLS

MARGIN = 4
"""Cells of outside kept round the shape's box: room to walk round its rim. A robot farther
out walks straight in until it is within the margin."""


def waypoints(
    blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray, target: np.ndarray, ahead: int
) -> tuple[np.ndarray, np.ndarray]:
    """For robots outside their shape, the cell `ahead` steps along the way round the shape to
    each one's `target`, and whether there is such a way (none for a robot beyond the margin
    round the shape, or for a target the seeds wall in)."""
    found = np.zeros(len(frame), dtype=bool)
    out = target.copy()
    for _, rows, low, size, fields, which in _grouped(blueprint, groups, target, frame, 1):
        at = frame[rows] - low
        reached = _walk(fields, which, at, size[0], size[1], ahead)
        found[rows] = reached
        out[rows[reached]] = at[reached] + low
    return out, found


def waypoint_round(
    blueprint: Blueprint,
    group: int,
    frame: np.ndarray,
    target: np.ndarray,
    ahead: int,
    walls: np.ndarray,
) -> tuple[np.ndarray, bool]:
    """`waypoints` for one robot that also never steps onto the frame cells `walls` ``(k, 2)``
    (robots it sees but does not hear: stalled ones stand there for good). Its own field,
    worked out for it alone: the kept ones are shared by every robot routing to a target."""
    low, size = _box(blueprint, group)
    at = (frame - low).reshape(1, 2)
    field = _field(blueprint, group, int(target[0]), int(target[1]), walls=walls - low)
    reached = _walk(field.reshape(1, -1), np.zeros(1, dtype=np.int64), at, size[0], size[1], ahead)
    return at[0] + low, bool(reached[0])


@njit
def _walk(
    fields: np.ndarray, which: np.ndarray, at: np.ndarray, rows: int, columns: int, ahead: int
) -> np.ndarray:  # pragma: no cover (compiled)
    """`waypoints` robot by robot: each cell `at` ``(k, 2)`` (box coordinates), moved in place
    `ahead` steps down its field `which`, each to the neighbour of least cost, the first of
    equals in move order (none if none costs less than its cell); whether each ends on a cell
    with a route. Five numpy lookups a step, over every robot, cost `local-swap` 3 ms a step
    at 10,000 robots."""

    def cost(field: np.ndarray, x: int, y: int) -> float:
        return field[x * columns + y] if 0 <= x < rows and 0 <= y < columns else np.inf

    reached = np.empty(len(at), dtype=np.bool_)
    for i in range(len(at)):
        field = fields[which[i]]
        x, y = at[i, 0], at[i, 1]
        best = cost(field, x, y)  # the cost of the cell it is on
        for _ in range(ahead):
            step = 0
            for direction in range(1, len(STEPS)):
                there = cost(field, x + STEPS[direction, 0], y + STEPS[direction, 1])
                if there < best:
                    step, best = direction, there
            x, y = x + STEPS[step, 0], y + STEPS[step, 1]
        at[i, 0], at[i, 1] = x, y
        reached[i] = np.isfinite(best)
    return reached


def costs(
    blueprint: Blueprint, groups: np.ndarray, cells: np.ndarray, target: np.ndarray
) -> np.ndarray:
    """``(n, k)``: for each robot, the route cost to its `target` ``(n, 2)`` from each of its
    frame `cells` ``(n, k, 2)`` (a way round the shape crossing fewer shape cells costs less,
    then a shorter one; inf off the margin round the shape)."""
    out = np.full(cells.shape[:2], np.inf)
    for _, rows, low, size, fields, which in _grouped(blueprint, groups, target, cells):
        k = cells.shape[1]
        at = (cells[rows] - low).reshape(-1, 2)
        out[rows] = _distance(fields, np.repeat(which, k), at, size).reshape(-1, k)
    return out


def ways(
    blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray, target: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each robot's way round the shape to its `target` from where it stands: how many free
    cells it walks, and how many more shape cells it crosses than the fewest that any way in
    from outside must (more: the shape walls the robot off from the target). inf: no way, or
    the robot is off the margin."""
    walked, walled = np.full(len(frame), np.inf), np.full(len(frame), np.inf)
    for group, rows, low, size, fields, which in _grouped(blueprint, groups, target, frame):
        cost = _distance(fields, which, frame[rows] - low, size)
        way = rows[np.isfinite(cost)]
        cost = cost[np.isfinite(cost)]
        crossed = np.floor(cost / size.prod())  # a shape cell costs more than any walk
        walked[way] = cost - crossed * size.prod()
        ends = target[way] - low
        walled[way] = crossed - _fewest_crossed(blueprint, group)[ends[:, 0], ends[:, 1]]
    return walked, walled


def _grouped(
    blueprint: Blueprint, groups: np.ndarray, target: np.ndarray, cells: np.ndarray, reach: int = 0
) -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per group: the group, the rows of its robots that a field can tell anything (one of
    their frame `cells` ``(n, 2)`` or ``(n, k, 2)`` on its box or within `reach` moves of it),
    its box's low corner and size, the route fields (`_Fields`), and which field is each
    robot's. A field has nothing for a robot off the box: 804 of the 849 fields that
    `local-swap` worked out at 10,000 robots (steps 101 to 120) were for robots beyond the
    margin round the shape, who walk straight in."""
    for group in np.unique(groups).tolist():
        low, size = _box(blueprint, group)
        rows = np.flatnonzero(groups == group)
        local = cells[rows].reshape(len(rows), -1, 2) - low
        off = (np.maximum(-local, 0) + np.maximum(local - (size - 1), 0)).sum(axis=2)
        rows = rows[(off <= reach).any(axis=1)]
        if not len(rows):
            continue
        pool = _fields(blueprint, group)
        which = pool.slots(target[rows])
        yield group, rows, low, size, pool.fields, which


def _distance(
    fields: np.ndarray, which: np.ndarray, at: np.ndarray, size: np.ndarray
) -> np.ndarray:
    """Each robot's route cost to its target at cells `at` (inf off the box)."""
    inside = ((at >= 0) & (at < size)).all(axis=1)
    distance = np.full(len(at), np.inf)
    distance[inside] = fields[which[inside], at[inside, 0] * size[1] + at[inside, 1]]
    return distance


@functools.lru_cache(maxsize=16)
def _box(blueprint: Blueprint, group: int) -> tuple[np.ndarray, np.ndarray]:
    """The low corner and size of the group's shape box (seeds included), with the margin."""
    cells = np.concatenate([blueprint.cells[group], SEED_CELLS])
    low = cells.min(axis=0) - MARGIN
    return low, cells.max(axis=0) + MARGIN + 1 - low


@functools.lru_cache(maxsize=16)
def _fewest_crossed(blueprint: Blueprint, group: int) -> np.ndarray:
    """Per cell of the box, the fewest shape cells a way in from outside crosses to reach it,
    itself included (0 outside): its taxicab distance to the nearest cell neither shape nor
    seed."""
    low, size = _box(blueprint, group)
    walls = np.zeros(size, dtype=bool)
    for cells in (blueprint.cells[group], SEED_CELLS):
        walls[cells[:, 0] - low[0], cells[:, 1] - low[1]] = True
    return scipy.ndimage.distance_transform_cdt(walls, metric="taxicab")


@functools.lru_cache(maxsize=16)
def _step_costs(blueprint: Blueprint, group: int) -> tuple[np.ndarray, np.ndarray]:
    """Per cell of the box and a border one cell wide round it, row by row, what a route pays
    to step onto it: 1 onto a free cell, onto a shape cell more than any way round through
    free cells (the box's cell count), so a route crosses as few shape cells as it can; and
    which cells are walls, never crossed: the seeds and the border (`_cheapest`)."""
    low, size = _box(blueprint, group)
    shape = np.zeros(size + 2, dtype=bool)
    cells = blueprint.cells[group] - low + 1
    shape[cells[:, 0], cells[:, 1]] = True
    seeds = np.zeros(size + 2, dtype=bool)
    seeds[SEED_CELLS[:, 0] - low[0] + 1, SEED_CELLS[:, 1] - low[1] + 1] = True
    walls = seeds.copy()
    walls[[0, -1], :] = walls[:, [0, -1]] = True
    return np.where(~shape & ~seeds, 1.0, float(size.prod())).ravel(), walls.ravel()


FIELD_BYTES = 1 << 29
"""Memory the route fields of one group's shape may keep (512 MB), the least recently used
given up first. Robots stuck outside a 10,000-robot letter S routed to 1,100 distinct
targets a step: with room for 512 fields every one was worked out again every step (2.2 s
a step)."""


class _Fields:
    """The route fields of one group's shape, one row per target (`_field`), kept while there
    is room (`FIELD_BYTES`), or while a single step needs them. The array is the whole room
    from the start, never written: the system gives a row memory when it is first written, so
    rows never used cost nothing (`_unwritten`). Grown by the rows a step lacked, it was
    copied whole nearly every step (36 ms a step at 10,000 robots); doubled, the copy to 2,176
    rows still cost its step 330 ms (`local-swap` on the 10,000-robot S)."""

    def __init__(self, blueprint: Blueprint, group: int) -> None:
        self.blueprint, self.group = blueprint, group
        self.cells = int(_box(blueprint, group)[1].prod())
        self.fields = _unwritten(max(1, FIELD_BYTES // (8 * self.cells)), self.cells)
        self.room = len(self.fields)
        self.slot: dict[tuple[int, int], int] = {}  # in order of last use
        self.used = 0  # rows that have held a field: `fields[used:]` was never written
        self.free: list[int] = []  # rows below `used` that hold no kept field

    def slots(self, targets: np.ndarray) -> np.ndarray:
        """Each target's row in `fields`, working out the fields not kept."""
        ends, which = _unique_cells(targets)
        keys = [(x, y) for x, y in ends.tolist()]
        for key in keys:  # the ones used now last, so they are given up last
            if key in self.slot:
                self.slot[key] = self.slot.pop(key)
        missing = [key for key in keys if key not in self.slot]
        over = len(self.slot) + len(missing) - self.room
        if over > 0:
            needed = set(keys)
            for key in [key for key in itertools.islice(self.slot, over) if key not in needed]:
                self.free.append(self.slot.pop(key))
        lacking = len(missing) - len(self.free) - (len(self.fields) - self.used)
        if lacking > 0:  # this step alone needs more fields than the room holds
            grown = _unwritten(len(self.fields) + lacking, self.cells, at_least=True)
            grown[: self.used] = self.fields[: self.used]  # the rows never written stay so
            self.fields = grown
        for key in missing:
            if self.free:
                row = self.free.pop()
            else:
                row, self.used = self.used, self.used + 1
            _field(self.blueprint, self.group, *key, self.fields[row])
            self.slot[key] = row
        return np.array([self.slot[key] for key in keys], dtype=np.int64)[which.reshape(-1)]


def _unwritten(rows: int, columns: int, at_least: bool = False) -> np.ndarray:
    """A float array (of zeros) that the system backs a small page at a time as it is
    first written. numpy asks for huge pages for an array over 4 MB, and on a virtual machine
    a row's first write into a fresh 2 MB page cost up to 0.5 ms, against 0.1 ms in small
    pages: `local-swap` at 10,000 robots works out some 25 new fields a step. Where the
    system will not map `rows` rows (a limit on address space, strict overcommit), as many as
    it will, halving, unless `at_least`: 512 MB a group refused a run that needs far less."""
    while True:
        try:
            room = mmap.mmap(-1, rows * columns * 8)
        except (OSError, MemoryError):
            if at_least or rows == 1:
                raise
            rows //= 2
        else:
            return np.frombuffer(room, dtype=np.float64).reshape(rows, columns)


def _unique_cells(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`np.unique(cells, axis=0, return_inverse=True)` for cells ``(k, 2)``, through one
    integer a cell that sorts as the rows do: the row-wise sort cost a 10,000-robot
    `mean-shift` step 7 ms."""
    if not len(cells):
        return cells.reshape(0, 2), np.zeros(0, dtype=np.int64)
    low = cells.min(axis=0)
    height = int(cells[:, 1].max() - low[1]) + 1
    keys, which = np.unique((cells[:, 0] - low[0]) * height + (cells[:, 1] - low[1]),
                            return_inverse=True)  # fmt: skip
    return np.stack([keys // height + low[0], keys % height + low[1]], axis=1), which


def _fields(blueprint: Blueprint, group: int) -> _Fields:
    """The kept route fields of one group's shape."""
    pools = _pools(blueprint)
    if group not in pools:
        pools[group] = _Fields(blueprint, group)
    return pools[group]


@functools.lru_cache(maxsize=1)
def _pools(blueprint: Blueprint) -> dict[int, _Fields]:
    """The route fields of the shapes robots know now, per group: a reshape gives the robots
    a new blueprint, and the fields of the old one go, so a session that reshapes again and
    again keeps one set (each can fill `FIELD_BYTES`)."""
    return {}


def _field(
    blueprint: Blueprint,
    group: int,
    x: int,
    y: int,
    into: np.ndarray | None = None,
    walls: np.ndarray | None = None,
) -> np.ndarray:
    """The cost of a route to frame cell ``(x, y)`` from each cell of the box, counting the
    step into that cell too, so a route goes to the neighbour of least cost (inf: no route,
    or the target is off the box), row by row `into` a flat array (a new one if None): a
    field worked out apart and copied into its row cost `local-swap` at 10,000 robots about
    a millisecond a step. `walls`: box cells never stepped on, besides the seeds."""
    low, size = _box(blueprint, group)
    field = np.empty(int(size.prod())) if into is None else into
    local = np.array([x, y]) - low
    if not ((local >= 0) & (local < size)).all():
        field[:] = np.inf
        return field
    cost, blocked = _step_costs(blueprint, group)
    width = int(size[1]) + 2
    if walls is not None:
        inside = walls[((walls >= 0) & (walls < size)).all(axis=1)] + 1
        blocked = blocked.copy()
        blocked[inside[:, 0] * width + inside[:, 1]] = True
    _cheapest(cost, blocked, int((local[0] + 1) * width + local[1] + 1), width, field)
    return field


@njit
def _cheapest(
    cost: np.ndarray, walls: np.ndarray, start: int, width: int, best: np.ndarray
) -> None:  # pragma: no cover (compiled)
    """Per cell of a box laid out row by row, the least cost of a path of steps between side
    neighbours to `start` (inf: none), paying the `cost` of every cell on it, both ends too,
    never into or out of a wall, written into `best`. `cost` and `walls` cover the box and a
    border of walls one cell wide round it, `width` cells a row (`best` the box alone): with
    the border a step needs no test for the box's edges, and a field took 101 us instead of
    118 us on the 10,000-robot letter S's box. Dijkstra's method, with its frontier kept in
    three queues instead of a heap: every step costs 1 or the cost of a shape cell, which is
    more than any run of free cells, so the frontier falls into levels by shape cells
    crossed, each walked breadth first, and each queue stays in order of cost by itself.
    scipy's Dijkstra on the same graph took eight times as long, and the fields are the
    same."""
    n = len(cost)
    paid_at = np.full(n, np.inf)  # `best` over the bordered box, less each cell's own cost
    paid_at[start] = 0.0
    room = 4 * n + 1  # a cell enters a queue at most once from each neighbour
    level, level_cost = np.empty(room, dtype=np.int64), np.empty(room)  # reached crossing in
    walk, walk_cost = np.empty(room, dtype=np.int64), np.empty(room)  # walked on in the level
    deeper, deeper_cost = np.empty(room, dtype=np.int64), np.empty(room)  # the next level
    level[0], level_cost[0], in_level = start, 0.0, 1
    while in_level:
        taken = walked = in_walk = in_deeper = 0
        while taken < in_level or walked < in_walk:
            if walked == in_walk or (taken < in_level and level_cost[taken] <= walk_cost[walked]):
                cell, paid = level[taken], level_cost[taken]
                taken += 1
            else:
                cell, paid = walk[walked], walk_cost[walked]
                walked += 1
            if paid > paid_at[cell] or walls[cell]:
                continue  # reached more cheaply since, or a wall (the start may be a seed)
            onward = paid + cost[cell]
            free = cost[cell] == 1.0
            for step in (-width, width, -1, 1):
                other = cell + step
                if not walls[other] and onward < paid_at[other]:
                    paid_at[other] = onward
                    if free:
                        walk[in_walk], walk_cost[in_walk] = other, onward
                        in_walk += 1
                    else:
                        deeper[in_deeper], deeper_cost[in_deeper] = other, onward
                        in_deeper += 1
        level, deeper = deeper, level
        level_cost, deeper_cost = deeper_cost, level_cost
        in_level = in_deeper
    paid_at += cost
    inside = paid_at.reshape(n // width, width)[1:-1, 1:-1]
    best.reshape(inside.shape)[:] = inside

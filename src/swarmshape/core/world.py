"""The arena and what is fixed in it: each group's target cells and seed robots.

World cells are integer ``(x, y)``, y growing downward; grids over the arena are indexed
``[x, y]`` with shape ``(width, height)``, the layout pygame's surfarray uses too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy

from swarmshape.core.shape import MAX_ARENA_CELLS, SEED_CELLS, Pose, Shape, frozen
from swarmshape.core.snapshot import Snapshot, prefixed
from swarmshape.errors import InputError

MARGIN = 3
"""Free cells kept around everything placed, so agents can always pass around it."""

ROOM_PER_AGENT = 5
"""An automatic arena has this many free cells per agent, so waiting agents stay sparse."""

ASPECT = 1.6
"""Automatic arenas are at least this much wider than tall, to fill a landscape window."""

GROUP_GAP = 4

START_LAYOUTS = ("packed", "scatter")
"""Start layouts by name: ``packed`` puts each group's robots in a block against its seeds, on
the side away from its shape (as in the Kilobot self-assembly experiments); ``scatter`` draws
random free cells (the default)."""

START_BLOCK = 2**20
"""Arena cells looked through at a time when start cells are picked."""

MAX_AGENTS = 1_000_000
"""A cap that keeps memory bounded (a million agents need about a gigabyte all told); the
arena's is `MAX_ARENA_CELLS`."""


class WorldError(InputError):
    """A layout that cannot be built; the message says what to change."""


@dataclass(frozen=True, eq=False)
class GroupSpec:
    """One group as a scenario describes it, before fitting and placement."""

    name: str
    shape: Shape
    colour: tuple[int, int, int]
    agents: int | None = None
    pose: Pose | None = None


@dataclass(frozen=True, eq=False)
class Group:
    """A placed group: its fitted shape, its world target cells and its seeds."""

    name: str
    colour: tuple[int, int, int]
    shape: Shape
    pose: Pose
    agents: int
    frame_cells: np.ndarray
    targets: np.ndarray
    seeds: np.ndarray

    def __post_init__(self) -> None:
        for array in (self.frame_cells, self.targets, self.seeds):
            frozen(array)

    def packed(self) -> np.ndarray:
        """World cells ``(agents, 2)`` of a block of this group's robots packed against its
        seeds: a near-square block above the seed L in the seed frame (rows ``y <= -2``, its
        right column at ``x = 1``), filled from the row touching the seeds outward."""
        width = max(1, math.ceil(math.sqrt(self.agents)))
        k = np.arange(self.agents)
        frame = np.column_stack([1 - k % width, -2 - k // width])
        return self.pose.to_world(frame)

    @classmethod
    def placed(
        cls, name: str, colour: tuple[int, int, int], shape: Shape, pose: Pose, agents: int
    ) -> Group:
        """The group with its shape's cells and its seeds put where `pose` says."""
        frame = shape.cells
        return cls(
            name,
            colour,
            shape,
            pose,
            agents,
            frame,
            pose.to_world(frame),
            pose.to_world(SEED_CELLS),
        )


@dataclass(frozen=True, eq=False)
class World:
    """All groups in one arena of ``size = (width, height)`` cells, and what the run is called."""

    size: tuple[int, int]
    groups: tuple[Group, ...]
    name: str = "swarm"
    targets: np.ndarray = field(init=False)
    target_group: np.ndarray = field(init=False)
    seeds: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        targets = np.concatenate([g.targets for g in self.groups])
        sizes = [len(g.targets) for g in self.groups]
        object.__setattr__(self, "targets", frozen(targets))
        object.__setattr__(self, "target_group", frozen(np.repeat(np.arange(len(sizes)), sizes)))
        object.__setattr__(self, "seeds", frozen(np.concatenate([g.seeds for g in self.groups])))

    @property
    def agents(self) -> int:
        return sum(g.agents for g in self.groups)

    def targets_of(self, group: int) -> slice:
        """Where `group`'s targets lie in `targets`: together, the groups in order."""
        ends = np.searchsorted(self.target_group, [group, group + 1])
        return slice(int(ends[0]), int(ends[1]))

    def reshaped(self, group: int, shape: Shape, pose: Pose) -> World:
        """The same arena with one group's shape (and seed pose) replaced; checked as new."""
        old = self.groups[group]
        groups = list(self.groups)
        groups[group] = Group.placed(old.name, old.colour, shape, pose, old.agents)
        world = World(self.size, tuple(groups), self.name)
        _validate(world, starts=False)
        return world

    def snapshot(self) -> dict[str, Any]:
        """What defines the world; the cells follow from each group's shape and pose."""
        values: dict[str, Any] = {"name": self.name, "size": list(self.size)}
        values["groups"] = len(self.groups)
        for index, g in enumerate(self.groups):
            pose = [g.pose.x, g.pose.y, g.pose.rotation]
            values |= prefixed(
                f"group{index}",
                {"name": g.name, "colour": list(g.colour), "grid": g.shape.grid,
                 "scale": g.shape.scale, "origin": list(g.shape.origin), "pose": pose,
                 "agents": g.agents},
            )  # fmt: skip
        return values

    @classmethod
    def restored(cls, saved: Snapshot) -> World:
        """The world `snapshot` described, checked as a new one would be."""
        size = saved.integers("size", 2, 1, MAX_ARENA_CELLS)
        groups = []
        for index in range(saved.integer("groups", 1, 1000)):
            part = saved.part(f"group{index}")
            grid = part.array("grid", bool, (None, None))
            origin = part.integers("origin", 2)
            shape = Shape(grid, part.number("scale", 0, 1), (origin[0], origin[1]))
            x, y, rotation = part.integers("pose", 3)
            if rotation % 90:
                raise part.error("pose", "turns by other than quarter turns")
            agents = part.integer("agents", 0, MAX_AGENTS)
            red, green, blue = part.integers("colour", 3, 0, 255)
            colour = (red, green, blue)
            groups.append(
                Group.placed(part.text("name"), colour, shape, Pose(x, y, rotation), agents)
            )
        world = cls((size[0], size[1]), tuple(groups), saved.text("name"))
        _validate(world, starts=False)
        return world

    def mask(self, cells: np.ndarray) -> np.ndarray:
        """A ``(width, height)`` boolean grid, True at `cells`."""
        grid = np.zeros(self.size, dtype=bool)
        grid[cells[:, 0], cells[:, 1]] = True
        return grid

    def depth(self) -> np.ndarray:
        """For each target, how many cells it lies inside its group's shape: the lattice
        distance to the nearest cell that is not the shape's (1 on the rim)."""
        depth = np.zeros(len(self.targets), dtype=np.int64)
        for group in range(len(self.groups)):
            mine = self.target_group == group
            if not mine.any():
                continue
            # within the group's box and a ring round it, which holds the nearest cell that is
            # not the shape's: the measure of the shape, not of the arena
            cells = self.targets[mine] - (self.targets[mine].min(axis=0) - 1)
            inside = np.zeros(tuple(cells.max(axis=0) + 2), dtype=bool)
            inside[cells[:, 0], cells[:, 1]] = True
            field = scipy.ndimage.distance_transform_cdt(inside, metric="taxicab")
            depth[mine] = field[cells[:, 0], cells[:, 1]]
        return depth

    def outside(self) -> np.ndarray:
        """Free cells connected to the arena border: where agents can come from."""
        free = ~(self.mask(self.targets) | self.mask(self.seeds))
        labels, count = scipy.ndimage.label(free)
        reached = np.zeros(count + 1, dtype=bool)
        reached[np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = True
        reached[0] = False  # not free
        return reached[labels]

    def start_mask(self) -> np.ndarray:
        """Per arena cell, whether agents may start there: outside, and not touching a target
        or a seed."""
        placed = scipy.ndimage.binary_dilation(
            self.mask(self.targets) | self.mask(self.seeds), structure=np.ones((3, 3))
        )
        return self.outside() & ~placed

    def start_cells(self) -> np.ndarray:
        """The cells ``(k, 2)`` where agents may start (see `start_mask`), in ``[x, y]`` order."""
        return np.argwhere(self.start_mask())


def cells_at(mask: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """The cells ``(k, 2)`` of `mask` at the places `chosen` of its ``[x, y]`` order (of
    ``np.argwhere(mask)``), found without listing them all: 16 bytes a cell, 400 MB on the
    largest arena for the 20 robots that start there."""
    flat = mask.reshape(-1)
    starts = np.arange(0, len(flat), START_BLOCK)
    before = np.cumsum(np.add.reduceat(flat, starts, dtype=np.int64))
    block = np.searchsorted(before, chosen, side="right")
    places = np.empty(len(chosen), dtype=np.int64)
    for index in np.unique(block).tolist():
        mine = block == index
        inside = np.flatnonzero(flat[starts[index] : starts[index] + START_BLOCK])
        earlier = before[index - 1] if index else 0
        places[mine] = starts[index] + inside[chosen[mine] - earlier]
    return np.column_stack(np.unravel_index(places, mask.shape))


def blank_world(
    size: tuple[int, int], pose: Pose, name: str, colour: tuple[int, int, int]
) -> World:
    """An arena with one group's seeds and no shape yet: the editor's empty canvas."""
    group = Group.placed(name, colour, Shape(np.zeros((0, 0), dtype=bool)), pose, 0)
    world = World(size, (group,), name)
    _validate(world, starts=False, blank=True)
    return world


def build_world(
    specs: list[GroupSpec],
    arena: tuple[int, int] | None = None,
    name: str = "swarm",
    packed: bool = False,
) -> World:
    """Fit every group's shape to its agents, place it, and size the arena if not given (with
    room for each group's packed block too if `packed`)."""
    if not specs:
        raise WorldError("a scenario needs at least one group")
    groups = _place(specs)
    if arena is None:
        groups, arena = _auto_arena(groups, packed)
    world = World(arena, tuple(groups), name)
    _validate(world, starts=not packed)
    if packed:
        packed_start(world)
    return world


def packed_start(world: World) -> np.ndarray:
    """Start cells ``(agents, 2)``: every group's robots in a block against its seeds (see
    `Group.packed`), checked to lie in the arena on free cells."""
    cells = np.concatenate([g.packed() for g in world.groups])
    width, height = world.size
    inside = (cells >= 0).all(axis=1) & (cells < np.array(world.size)).all(axis=1)
    if not inside.all():
        raise WorldError(
            f"the packed start does not fit in the {width}x{height} arena; enlarge the arena"
        )
    taken = world.mask(world.targets) | world.mask(world.seeds)
    if taken[cells[:, 0], cells[:, 1]].any() or len(np.unique(cells, axis=0)) < len(cells):
        raise WorldError(
            "the packed start overlaps a shape or another group's robots; move a seed pose"
        )
    return cells


def _place(specs: list[GroupSpec]) -> list[Group]:
    groups, next_x = [], 0
    for spec in specs:
        agents = spec.shape.count if spec.agents is None else spec.agents
        if agents < 1:
            raise WorldError(f"group {spec.name!r}: agents must be at least 1, got {agents}")
        if agents > MAX_AGENTS:
            raise WorldError(
                f"group {spec.name!r}: {agents:,} agents is more than the {MAX_AGENTS:,} "
                "swarmshape simulates; lower --agents or --cells"
            )
        shape = spec.shape.fitted(agents)
        pose = spec.pose
        if pose is None:  # side by side, left to right, each shape with its seeds at (x, 0)+
            frame = np.concatenate([SEED_CELLS, shape.cells])
            low, high = frame.min(axis=0), frame.max(axis=0)
            pose = Pose(next_x - int(low[0]), -int(low[1]))
            next_x += int(high[0] - low[0]) + 1 + GROUP_GAP
        groups.append(Group.placed(spec.name, spec.colour, shape, pose, agents))
    return groups


def _auto_arena(groups: list[Group], packed: bool = False) -> tuple[list[Group], tuple[int, int]]:
    """Shift everything to a margin from the origin and grow the arena to room and aspect."""
    blocks = [g.packed() for g in groups] if packed else []
    placed = np.concatenate([np.concatenate([g.targets, g.seeds]) for g in groups] + blocks)
    low, high = placed.min(axis=0), placed.max(axis=0) + 1
    width, height = (high - low) + 2 * MARGIN
    needed = len(placed) + ROOM_PER_AGENT * sum(g.agents for g in groups)
    while width * height < needed or width < ASPECT * height:
        if width < ASPECT * height:
            width += 1
        else:
            height += 1
    offset = MARGIN - low + (np.array([width, height]) - (high - low) - 2 * MARGIN) // 2
    dx, dy = int(offset[0]), int(offset[1])
    moved = [
        Group.placed(
            g.name, g.colour, g.shape, Pose(g.pose.x + dx, g.pose.y + dy, g.pose.rotation), g.agents
        )
        for g in groups
    ]
    return moved, (int(width), int(height))


def _validate(world: World, *, starts: bool = True, blank: bool = False) -> None:
    """Refuse a world that cannot run: an arena too small or too large, a group off it or with
    no cell to form (unless `blank`: the editor's canvas), overlapping groups, and (with
    `starts`) too little room to start the robots."""
    width, height = world.size
    if width < 1 or height < 1:
        raise WorldError(f"arena must be at least 1x1 cells, got {width}x{height}")
    if width * height > MAX_ARENA_CELLS:
        raise WorldError(
            f"arena {width}x{height} is larger than {MAX_ARENA_CELLS:,} cells; make it smaller"
        )
    for group in world.groups:
        if not blank and not len(group.targets):
            raise WorldError(f"group {group.name!r}: its shape has no cells; draw at least one")
        cells = np.concatenate([group.targets, group.seeds])
        if (cells < 0).any() or (cells >= np.array(world.size)).any():
            raise WorldError(
                f"group {group.name!r}: shape or seeds fall outside the {width}x{height} arena"
            )
    everything = np.concatenate([world.targets, world.seeds])
    if len(np.unique(everything, axis=0)) < len(everything):
        raise WorldError("groups overlap: two shapes or seed sets share a cell; move a seed pose")
    if starts and int(world.start_mask().sum()) < world.agents:
        raise WorldError(
            f"arena {width}x{height} has no room to start {world.agents} agents; enlarge the arena"
        )

"""`Swarm`: one run's robots as numpy arrays on the cell lattice, advanced one step at a time.

The swarm owns the physics: where every robot is, which cells it holds, how fast it goes, and
the guarantee that squares never overlap (a cell is claimed only when free, and an independent
audit counts overlaps from positions every step). What robots *want* comes from a `Driver` that
the plug-in provides: for a central strategy, `swarmshape.core.steering.Steering`. The core
never imports pygame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from swarmshape.core.audit import overlaps
from swarmshape.core.lattice import FREE, SEED, Lattice
from swarmshape.core.motion import STEPS, TOUCH, Limits, advance, positions, resolve_claims
from swarmshape.core.states import WAITING
from swarmshape.core.world import WorldError

if TYPE_CHECKING:
    from swarmshape.core.shape import Pose, Shape
    from swarmshape.core.world import World


@dataclass(frozen=True)
class Params:
    """Behaviour knobs shared by all robots."""

    limits: Limits = field(default_factory=Limits)
    wander_rate: float = 0.1
    """Chance per step that a resting spare robot tries a random step."""
    patience: int = 3
    """Steps a mover waits behind a resting robot before it replans; twice that, it sidesteps."""


class Driver(Protocol):
    """What a swarm asks of its driver, phase by phase; each plug-in kind brings its own."""

    def start(self) -> None:
        """The run begins (after the swarm is set up)."""

    def index_world(self) -> None:
        """The world's targets or seeds are new (at the start, and after a reshape)."""

    def decide(self) -> None:
        """Each robot that wants a next cell claims it, through `Swarm.claim`."""

    def arrived(self) -> None:
        """Robots have moved; note who reached what."""

    def completed(self, group: int) -> None:
        """Every target of `group` is filled."""

    def reshaped(self, renumber: np.ndarray) -> None:
        """The targets were renumbered after a shape change (-1: gone); mark `Swarm.filled`."""

    def hand_out(self, group: int) -> None:
        """After a shape change: send robots to the group's open cells."""

    @property
    def messages_sent(self) -> int: ...


class Plugin(Protocol):
    """A strategy (or any other plug-in kind): it names itself and drives a swarm."""

    name: str

    def drive(self, swarm: Swarm) -> Driver: ...


class Swarm:
    """One run: the world, the robots' arrays, the lattice they hold, and one random generator.

    A step has named phases: the driver decides and claims cells (`claim`), robots advance
    under the speed limits (`_move`), the driver sees who arrived, and the audit counts
    overlaps; a group whose targets are all filled is complete.
    """

    def __init__(
        self,
        world: World,
        plugin: Plugin,
        seed: int,
        params: Params | None = None,
        start: np.ndarray | None = None,
    ) -> None:
        self.world = world
        self.plugin = plugin
        self.seed = seed
        self.params = params or Params()
        self.rng = np.random.default_rng(seed)
        n = world.agents
        self.group = np.repeat(np.arange(len(world.groups)), [g.agents for g in world.groups])
        if start is None:  # random free cells, drawn from the run's one generator
            starts = world.start_cells()
            start = starts[self.rng.choice(len(starts), n, replace=False)]
        self.cell = np.array(start, dtype=np.int64)
        self.start_cell = self.cell.copy()
        self.direction = np.zeros(n, dtype=np.int64)
        """Direction index (see `STEPS`) of the cells reserved ahead."""
        self.ahead = np.zeros(n, dtype=np.int64)
        """Cells reserved ahead of the robot's own, along `direction`."""
        self.offset = np.zeros(n)
        """How far the robot has come from its cell's centre toward the next."""
        self.speed = np.zeros(n)
        self.distance = np.zeros(n)
        """Cells travelled."""
        self.state = np.full(n, WAITING, dtype=np.int8)
        self.lattice = Lattice(world.size)
        self.lattice.grid[self.cell[:, 0], self.cell[:, 1]] = np.arange(n)
        self.filled = np.zeros(len(world.targets), dtype=bool)
        """Targets with a robot settled on them."""
        self.step_count = 0
        self.overlap_total = 0
        self.overlaps = np.zeros(len(world.groups), dtype=np.int64)
        """Overlapping pairs summed over steps, per group (a pair counts for both its groups)."""
        self.completed_at: list[int | None] = [None] * len(world.groups)
        self.driver = plugin.drive(self)
        self._index_world()
        self.driver.start()

    def _index_world(self) -> None:
        """Everything derived from the world's targets and seeds (again after a reshape)."""
        world = self.world
        self.lattice.grid[world.seeds[:, 0], world.seeds[:, 1]] = SEED
        self.lattice.mark_targets(world.targets, world.target_group)
        self._targets_per_group = np.bincount(world.target_group, minlength=len(world.groups))
        seeds_per_group = [len(g.seeds) for g in world.groups]
        self._seed_group = np.repeat(np.arange(len(world.groups)), seeds_per_group)
        self.driver.index_world()

    # --- reading the run ------------------------------------------------------------------------

    @property
    def complete(self) -> bool:
        return bool(self.filled.all())

    def positions(self) -> np.ndarray:
        """Robot square centres ``(n, 2)`` in world units."""
        return positions(self.cell, self.direction, self.offset)

    def cells_under(self) -> np.ndarray:
        """The cell under each robot's centre ``(n, 2)``."""
        return np.floor(self.positions()).astype(np.int64)

    # --- one step -------------------------------------------------------------------------------

    def step(self) -> None:
        self.driver.decide()
        self._move()
        self.driver.arrived()
        self.step_count += 1
        self._audit()
        self._note_completion()

    def claim(self, robots: np.ndarray, directions: np.ndarray, origins: np.ndarray) -> np.ndarray:
        """Each robot asks for the cell one step in `direction` from the key `origin` (its own
        cell, or the last one it reserved); free cells go to one claimant each, at random.
        Return the winners, which hold their new cell from now on."""
        claim = directions > 0
        robots, directions = robots[claim], directions[claim]
        keys = origins[claim] + self.lattice.offsets[directions]
        wins = self.lattice.holder[keys] == FREE
        wins[wins] = resolve_claims(keys[wins], self.rng)
        winners = robots[wins]
        self.lattice.holder[keys[wins]] = winners
        self.ahead[winners] += 1
        self.direction[winners] = directions[wins]
        return winners

    def _move(self) -> None:
        """Advance every robot along its reserved run; a robot reaching the next centre gives
        up the cell behind it."""
        self.distance += advance(self.offset, self.speed, self.ahead, self.params.limits)
        arrived = np.flatnonzero((self.ahead > 0) & (self.offset >= TOUCH))
        self.lattice.holder[self.lattice.key(self.cell[arrived])] = FREE
        self.cell[arrived] += STEPS[self.direction[arrived]]
        self.ahead[arrived] -= 1
        self.offset[arrived] -= 1.0
        stopped = arrived[self.ahead[arrived] == 0]
        self.offset[stopped] = 0.0
        self.speed[stopped] = 0.0

    def _audit(self) -> None:
        """Count overlapping pairs of squares, seeds included, from the positions alone."""
        world = self.world
        i, j = overlaps(self.cell, self.direction, self.offset, world.seeds, world.size)
        if len(i) == 0:
            return
        owner = np.concatenate([self.group, self._seed_group])
        self.overlap_total += len(i)
        np.add.at(self.overlaps, owner[i], 1)
        cross = owner[i] != owner[j]
        np.add.at(self.overlaps, owner[j][cross], 1)

    def _note_completion(self) -> None:
        """Note the step at which each group's targets were all filled, and tell the driver."""
        if None not in self.completed_at:
            return
        filled = np.bincount(self.world.target_group[self.filled], minlength=len(self.world.groups))
        for g in np.flatnonzero(filled == self._targets_per_group).tolist():
            if self.completed_at[g] is None:
                self.completed_at[g] = self.step_count
                self.driver.completed(g)

    # --- changing the shape while it runs -------------------------------------------------------

    def reshape(self, group: int, shape: Shape, pose: Pose | None = None) -> None:
        """Form a new shape for `group` without a restart (the live editor's hand-over).

        Robots on cells that stay in the shape keep them and do not move; robots whose cells
        or targets went away wander; the strategy then hands out the open cells.
        """
        old = self.world
        new = old.reshaped(group, shape, pose or old.groups[group].pose)
        seeds = new.mask(new.seeds) & ~old.mask(old.seeds)
        if (self.lattice.grid[seeds] >= 0).any():
            raise WorldError("the seeds' new cells are taken by robots; move them elsewhere")
        self.filled = np.zeros(len(new.targets), dtype=bool)
        self.driver.reshaped(_renumbering(old.targets, new.targets, new.size))
        self.lattice.grid[old.mask(old.seeds)] = FREE
        self.world = new
        self._index_world()
        self.completed_at[group] = None
        self.driver.hand_out(group)


def _renumbering(old: np.ndarray, new: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """For each old target, the index of the new target on the same cell, or -1."""
    index = np.full(size, -1)
    index[new[:, 0], new[:, 1]] = np.arange(len(new))
    return index[old[:, 0], old[:, 1]]

"""`Swarm`: one run's robots as numpy arrays on the cell lattice, advanced one step at a time.

The swarm owns the physics: where every robot is, which cells it holds, how fast it goes, and
the guarantee that squares never overlap (a cell is claimed only when free, and an independent
audit counts overlaps from positions every step). What robots *want* comes from a `Driver` that
the plug-in provides: for a central strategy, `swarmshape.core.steering.Steering`. The core
never imports pygame.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import numpy.typing as npt
import scipy

from swarmshape.core.audit import Audit, new_scratch
from swarmshape.core.compiled import njit
from swarmshape.core.faults import Faults
from swarmshape.core.guard import PluginCode
from swarmshape.core.heap import keep_freed_memory
from swarmshape.core.lattice import FREE, SEED, WALL, Lattice
from swarmshape.core.motion import STEPS, Limits, move, positions, resolve_claims
from swarmshape.core.options import TEXT, option, spec_of
from swarmshape.core.perception import Senses
from swarmshape.core.snapshot import Snapshot, prefixed
from swarmshape.core.states import LOST, MOVING, SETTLED, STALLED, WAITING, WANDERING, State
from swarmshape.core.world import World, WorldError, cells_at
from swarmshape.errors import InputError

if TYPE_CHECKING:
    from swarmshape.core.plugin import Plugin
    from swarmshape.core.shape import Pose, Shape

MAX_STEP = 2**62
"""The most steps a run can count (its step numbers go into int64 arrays)."""

ARRAYS = ("cell", "start_cell", "direction", "ahead", "offset", "speed", "distance", "state",
          "filled", "overlaps", "leader", "pace")  # fmt: skip
"""Per-robot (and per-target, per-group) arrays that a saved run keeps."""


@dataclass(frozen=True)
class Params:
    """Behaviour knobs shared by all robots."""

    limits: Limits = field(default_factory=Limits)
    senses: Senses = field(default_factory=Senses)
    """How well a local program's robots sense and talk (the run's, not the program's)."""
    wander_rate: float = 0.1
    """Chance per step that a resting spare robot tries a random step."""
    patience: int = 3
    """Steps a mover waits behind a resting robot before it replans; twice that, it sidesteps."""
    speed_variation: float = option(
        0.0,
        "each robot's top speed is max_speed times a factor drawn once from [1 - this, 1] "
        "(real robots differ; slow ones make traffic jams)",
        at_least=0.0,
        at_most=0.9,
    )
    on_loss: str = option(
        "keep",
        "when faults leave a shape fewer robots than cells: keep its size (spares and idle "
        "robots heal it, cells no robot is left for stay open) or rescale (re-form it at the "
        "largest scale the survivors can fill)",
        kind=TEXT,
        choices=("keep", "rescale"),
    )

    def __post_init__(self) -> None:
        spec_of(Params, "speed_variation").check(self.speed_variation)
        spec_of(Params, "on_loss").check(self.on_loss)


@dataclass(frozen=True, eq=False)
class Shown:
    """What a driver can show of its robots besides where they are, for the viewer: it colours
    robots by `state` when `states` names them, prints the `values` (named `values_of`) on
    them, draws the radio `links` heard in the last step and a line from each robot that
    `believes` it knows where it is to the world cell it believes it is on."""

    plugin: str
    states: tuple[str, ...] = ()
    state: np.ndarray | None = None
    values_of: str | None = None
    values: np.ndarray | None = None
    links: tuple[np.ndarray, np.ndarray] | None = None
    """Pairs ``(robot, other)`` that heard each other (other ``>= n``: a seed)."""
    believes: tuple[np.ndarray, np.ndarray] | None = None
    """Which robots know where they are, and the world cell each believes it is on."""


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
        """The targets were renumbered after a shape change (-1: gone)."""

    def removed(self, robots: np.ndarray, stalled: bool) -> None:
        """A fault struck `robots`: they no longer act. Without `stalled` they are gone (state
        `LOST`, off the lattice); with it they stand where they are for good (state `STALLED`),
        obstacles to go around. The swarm has already unmarked the targets they had filled and
        the ones a stall made unreachable (`Swarm.dead`). Forget whatever the driver kept for
        them (targets, paths, messages to them) and send others to the open cells. The swarm
        calls it before it re-forms a group too short of robots at a smaller scale."""

    def hand_out(self, group: int) -> None:
        """After a shape change: send robots to the group's open cells."""

    @property
    def messages_sent(self) -> int: ...

    @property
    def quiet(self) -> bool:
        """The run has come to rest for good without forming its shape (the loop stops)."""

    def figures(self) -> dict[str, Any]:
        """What this kind of plug-in adds to a run's metrics."""

    def shown(self) -> Shown | None:
        """What the viewer may draw of the robots beyond their cells (None: nothing)."""

    def snapshot(self) -> dict[str, Any]:
        """The driver's state, as plain values."""

    def restore(self, saved: Snapshot) -> None:
        """Take back what `snapshot` saved (the swarm's own arrays are back already)."""


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
        faults: Faults | None = None,
    ) -> None:
        self._take(world, plugin, seed, params or Params())
        n = world.agents
        if start is None:  # random free cells, drawn from the run's one generator
            free = world.start_mask()
            start = cells_at(free, self.rng.choice(int(free.sum()), n, replace=False))
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
        self.leader = np.full(n, -1, dtype=np.int64)
        """The robot each robot follows into a cell it is leaving, or -1."""
        self.pace = np.ones(n)
        """Each robot's top speed as a fraction of the limit."""
        if self.params.speed_variation > 0:
            self.pace = self.rng.uniform(1.0 - self.params.speed_variation, 1.0, n)
        self.lattice = Lattice(world.size)
        self.lattice.grid[self.cell[:, 0], self.cell[:, 1]] = np.arange(n)
        self.filled = np.zeros(len(world.targets), dtype=bool)
        """Targets with a robot settled on them."""
        self.step_count = 0
        self.overlap_total = 0
        self.overlaps = np.zeros(len(world.groups), dtype=np.int64)
        """Overlapping pairs summed over steps, per group (a pair counts for both its groups)."""
        self.completed_at: list[int | None] = [None] * len(world.groups)
        self.faults = faults or Faults()
        self.faults.lost_at = np.full(n, -1, dtype=np.int64)
        self.dead = np.zeros(len(world.targets), dtype=bool)
        """Targets no robot can fill: held by a stalled robot, or cut off by stalled robots
        from every robot of their group that can still move (lost coverage)."""
        with self._code.running(" as the run started"):
            self.driver = plugin.drive(self)
            self._index_world()
            self.driver.start()

    def _take(self, world: World, plugin: Plugin, seed: int, params: Params) -> None:
        """What a swarm is given, whether it starts afresh or resumes."""
        keep_freed_memory()  # a step's large arrays reused, not faulted in again (`heap`)
        self.world = world
        self.plugin = plugin
        self._code = PluginCode.of(plugin)
        """Where the plug-in's code lives: a failure there is its own (see `core.guard`)."""
        self.seed = seed
        self.params = params
        self.rng = np.random.default_rng(seed)
        self.group = np.repeat(np.arange(len(world.groups)), [g.agents for g in world.groups])
        self._scratch = new_scratch(world.size)
        """A per-cell working array of -1 for the audit and the claims (left so after use)."""

    # --- saving and resuming --------------------------------------------------------------------

    def snapshot(self) -> dict[str, Any]:
        """Everything the next step depends on, as plain values (see `core.snapshot`)."""
        limits = self.params.limits
        values = {
            "seed": self.seed,
            "max_speed": limits.max_speed,
            "max_accel": limits.max_accel,
            "wander_rate": self.params.wander_rate,
            "patience": self.params.patience,
            "speed_variation": self.params.speed_variation,
            "on_loss": self.params.on_loss,
            "senses": dataclasses.asdict(self.params.senses),
            "rng": self.rng.bit_generator.state,
            "step": self.step_count,
            "overlap_total": self.overlap_total,
            "completed_at": self.completed_at,
            **{name: getattr(self, name) for name in ARRAYS},
            "holder": self.lattice.holder,
            "queued": self.lattice.queued,
        }
        values |= prefixed("world", self.world.snapshot())
        values |= prefixed("faults", self.faults.snapshot()) | {"dead": self.dead}
        with self._code.running(" while the run was saved"):
            return values | prefixed("driver", self.driver.snapshot())

    @classmethod
    def restored(cls, saved: Snapshot, plugin: Plugin) -> Swarm:
        """The swarm `snapshot` described, ready for its next step, driven by a fresh `plugin`
        of the kind it was saved with. Anything inconsistent is refused."""
        swarm = cls.__new__(cls)
        world = World.restored(saved.part("world"))
        max_speed = saved.number("max_speed", 0, 1)
        try:
            limits = Limits(max_speed, saved.number("max_accel", 0, max_speed))
        except InputError as error:
            raise saved.error("max_speed", f"and max_accel are not valid ({error})") from None
        wander_rate = saved.number("wander_rate", 0, 1)
        patience = saved.integer("patience", 1, 10**6)
        senses = saved.value("senses")
        if not isinstance(senses, dict) or set(senses) != {"radius", "distance_noise", "msg_loss"}:
            raise saved.error("senses", "is not a sensing radius, distance noise and message loss")
        try:
            senses = Senses(**senses)
        except InputError as error:
            raise saved.error("senses", f"are not valid ({error})") from None
        speed_variation = saved.number("speed_variation", 0, 0.9)
        on_loss = saved.text("on_loss")
        if not spec_of(Params, "on_loss").allows(on_loss):
            raise saved.error("on_loss", f"is {on_loss!r}, not keep or rescale")
        params = Params(limits, senses, wander_rate, patience, speed_variation, on_loss)
        swarm._take(world, plugin, saved.integer("seed", 0, 2**63 - 1), params)
        swarm._restore_arrays(saved)
        swarm._restore_rng(saved)
        swarm.step_count = saved.integer("step", 0, MAX_STEP)
        # a run never has overlapping robots: counted ones mean a crafted or damaged state
        swarm.overlap_total = saved.integer("overlap_total", 0, 0)
        completed = saved.value("completed_at")
        if not isinstance(completed, list) or len(completed) != len(world.groups):
            raise saved.error("completed_at", "does not have one entry per group")
        if not all(at is None or (type(at) is int and 0 <= at <= swarm.step_count)
                   for at in completed):  # fmt: skip
            raise saved.error("completed_at", "holds something other than steps of the run")
        swarm.completed_at = completed
        swarm.faults = Faults.restored(saved.part("faults"), world.agents, swarm.step_count)
        if not np.array_equal(swarm.faults.lost_at >= 0, swarm.state == LOST):
            raise saved.error("faults.lost_at", "disagrees with which robots are lost")
        with swarm._code.running(" while the run was resumed"):
            swarm.driver = plugin.drive(swarm)
            swarm._index_world()
            if not np.array_equal(saved.array("dead", bool, (len(world.targets),)), swarm.dead):
                raise saved.error("dead", "disagrees with where the stalled robots are")
            swarm.driver.restore(saved.part("driver"))
        return swarm

    def _restore_arrays(self, saved: Snapshot) -> None:
        n, width, height = self.world.agents, *self.world.size
        low, high = 0, max(width, height) - 1
        self.cell = saved.array("cell", np.int64, (n, 2), low, high)
        self.start_cell = saved.array("start_cell", np.int64, (n, 2), low, high)
        self.direction = saved.array("direction", np.int64, (n,), 0, len(STEPS) - 1)
        self.ahead = saved.array("ahead", np.int64, (n,), 0, 2)
        self.offset = saved.array("offset", np.float64, (n,), 0, 1)
        self.speed = saved.array("speed", np.float64, (n,), 0, 1)
        self.distance = saved.array("distance", np.float64, (n,), 0)
        self.state = saved.array("state", np.int8, (n,), 0, len(State) - 1)
        self.filled = saved.array("filled", bool, (len(self.world.targets),))
        self.overlaps = saved.array("overlaps", np.int64, (len(self.world.groups),), 0, 0)
        self.leader = saved.array("leader", np.int64, (n,), -1, n - 1)
        self.pace = saved.array("pace", np.float64, (n,), 0.1, 1)
        under_way = self.ahead > 0
        if (under_way & (self.direction == 0)).any():
            raise saved.error("direction", "is none for a robot with cells reserved ahead")
        if (~under_way & ((self.offset != 0) | (self.speed != 0))).any():
            raise saved.error("offset", "or speed puts a robot with no cell reserved on its way")
        self.lattice = Lattice(self.world.size)
        holder = saved.array("holder", np.int64, self.lattice.holder.shape, WALL, n - 1)
        queued = saved.array("queued", np.int64, self.lattice.queued.shape, FREE, n - 1)
        held = np.concatenate([self.cell + STEPS[self.direction] * k for k in (0, 1, 2)])
        present = self.state != LOST
        reserved = np.concatenate([present, self.ahead >= 1, self.ahead >= 2])
        reserved &= np.tile(present, 3)
        if (held[reserved] >= self.world.size).any() or (held[reserved] < 0).any():
            raise saved.error("cell", "puts a robot or its reservation outside the arena")
        keys, who = self.lattice.key(held[reserved]), np.tile(np.arange(n), 3)[reserved]
        lead = np.maximum(self.leader[who], 0)
        following = (queued[keys] == who) & (self.leader[who] >= 0) & (holder[keys] == lead)
        following &= self.lattice.key(self.cell[lead]) == keys
        accounted = (holder >= 0).sum() + (queued >= 0).sum() == len(keys)
        walls = self.lattice.holder == WALL
        seeds = self.lattice.key(self.world.seeds)
        if (
            not ((holder[keys] == who) | following).all()
            or not accounted
            or (self.leader >= 0).sum() != (queued >= 0).sum()
            or (holder[walls] != WALL).any()
            or (holder[seeds] != SEED).any()
        ):
            raise saved.error("holder", "disagrees with where the robots and seeds are")
        self.lattice.holder[:] = holder
        self.lattice.queued[:] = queued
        filled = self.world.targets[self.filled]
        resting = self.lattice.grid[filled[:, 0], filled[:, 1]]
        if ((resting < 0) | (self.state[np.maximum(resting, 0)] != SETTLED)).any():
            raise saved.error("filled", "marks a target that no settled robot rests on")

    def _restore_rng(self, saved: Snapshot) -> None:
        try:
            self.rng.bit_generator.state = saved.value("rng")
        except (TypeError, ValueError, KeyError, OverflowError):
            raise saved.error("rng", "is not a random generator's state") from None

    def _index_world(self) -> None:
        """Everything derived from the world's targets and seeds (again after a reshape)."""
        world = self.world
        self.lattice.grid[world.seeds[:, 0], world.seeds[:, 1]] = SEED
        self.lattice.mark_targets(world.targets, world.target_group)
        seeds_per_group = [len(g.seeds) for g in world.groups]
        self._seed_group = np.repeat(np.arange(len(world.groups)), seeds_per_group)
        self.target_at = np.full(world.size, -1, dtype=np.int32)  # up to 25,000,000 targets
        self.target_at[world.targets[:, 0], world.targets[:, 1]] = np.arange(len(world.targets))
        """The index of the target at each cell, -1 where there is none."""
        self.dead = self._find_dead()
        self._auditor = Audit(world.size)  # the seeds may have moved
        self.driver.index_world()

    # --- the robots' states: drivers say what happened, only the swarm writes it ---------------

    def settle(self, robots: np.ndarray) -> None:
        """`robots` rest on targets of their own group and settle: those targets are filled."""
        self.state[robots] = SETTLED
        self.filled[self._target_under(robots)] = True

    def dispatch(self, robots: np.ndarray) -> None:
        """`robots` set off for a target; a settled one leaves its target open."""
        settled = robots[self.state[robots] == SETTLED]
        under = self._target_under(settled)
        self.filled[under[under >= 0]] = False
        self.state[robots] = MOVING

    def release(self, robots: np.ndarray) -> None:
        """`robots` have nothing left to do and wander."""
        self.state[robots] = WANDERING

    def wait(self, robots: np.ndarray) -> None:
        """`robots` wait for a target."""
        self.state[robots] = WAITING

    def settle_exactly(self, settled: np.ndarray, filling: np.ndarray | None = None) -> None:
        """Exactly the robots of the mask `settled` are settled (a local program says so anew
        each step); the others that can act are moving if under way, else waiting. Those of
        `filling` fill the targets they rest on as the settled do, without being settled."""
        working = self._mobile()
        self.state[working] = np.where(self.ahead[working] > 0, MOVING, WAITING)
        self.state[working & settled] = SETTLED
        self._refill(None if filling is None else working & filling)

    def _refill(self, filling: np.ndarray | None = None) -> None:
        """A target is filled while a settled robot of its group (or one of `filling`) rests
        on it."""
        self.filled[:] = False
        robots = self.state == SETTLED if filling is None else (self.state == SETTLED) | filling
        under = self._target_under(np.flatnonzero(robots))
        self.filled[under[under >= 0]] = True

    def _target_under(self, robots: np.ndarray) -> np.ndarray:
        """The target of its own group each robot rests on, or -1."""
        at = self.target_at[self.cell[robots, 0], self.cell[robots, 1]]
        mine = (at >= 0) & (self.world.target_group[np.maximum(at, 0)] == self.group[robots])
        return np.where(mine, at, -1)

    # --- reading the run ------------------------------------------------------------------------

    @property
    def complete(self) -> bool:
        """Every group's shape is whole (see `_whole`)."""
        return all(self._whole(g) for g in range(len(self.world.groups)))

    @property
    def stranded(self) -> bool:
        """A shape is not whole and nothing can change any more: every group's shape is whole,
        or faults left the group no robot that can move or is still under way, or no target
        its robots can reach while no stalled robot coasts and no failure rate may open one
        (re-forming leaves that only when every robot that can move stands on another group's
        shape, where a live change to that shape may have put it)."""
        whole = [self._whole(g) for g in range(len(self.world.groups))]
        # the cheap tests first: this runs every step, and under way most robots can move
        return not all(whole) and all(
            whole[g]
            or not _any_able(self.state, self.ahead, self.group, g)
            or (
                self.dead[self.world.targets_of(g)].all()
                and self.faults.rate == 0
                and self._walls_still()
            )
            for g in range(len(whole))
        )

    def movable(self, group: int) -> int:
        """How many robots of `group` can still move (neither removed nor stalled): what a new
        shape for it may ask of it."""
        return int((self._mobile() & (self.group == group)).sum())

    @property
    def present(self) -> np.ndarray:
        """Robots still in the run (not removed by a fault)."""
        return self.state != LOST

    def positions(self) -> np.ndarray:
        """Robot square centres ``(n, 2)`` in world units."""
        return positions(self.cell, self.direction, self.offset)

    def cells_under(self) -> np.ndarray:
        """The cell under each robot's centre ``(n, 2)``."""
        return np.floor(self.positions()).astype(np.int64)

    # --- one step -------------------------------------------------------------------------------

    def step(self) -> None:
        with self._code.running(f" at step {self.step_count}"):
            if self.faults.scheduled:
                self._strike()
            coasting = np.flatnonzero((self.state == STALLED) & (self.ahead > 0))
            self.driver.decide()
            self._move()
            self.driver.arrived()
            self.step_count += 1
            if len(coasting):
                self._walls_moved(coasting)
            self._audit()
            self._note_completion()
            self.faults.note(self.step_count, self.complete)

    def figures(self) -> dict[str, Any]:
        """What the plug-in's kind adds to the run's metrics (see `Driver.figures`)."""
        with self._code.running(" when the run was measured"):
            return self.driver.figures()

    def claim(self, robots: np.ndarray, directions: np.ndarray, origins: np.ndarray) -> np.ndarray:
        """Each robot asks for the cell one step in `direction` from the key `origin` (its own
        cell, or the last one it reserved). Free cells, and cells whose robot is leaving them the
        same way (the claimant then follows it, see `followable`), go to one claimant each, at
        random. Return the winners, which hold (or are queued for) their new cell from now on."""
        claim = directions > 0
        robots, directions = robots[claim], directions[claim]
        keys = origins[claim] + self.lattice.offsets[directions]
        holder = self.lattice.holder[keys]
        follows = self.followable(keys, directions)
        wins = (holder == FREE) | follows
        wins[wins] = resolve_claims(keys[wins], self.rng, self._scratch)
        winners = robots[wins]
        queued = wins & follows
        self.lattice.holder[keys[wins & ~queued]] = robots[wins & ~queued]
        self.lattice.queued[keys[queued]] = robots[queued]
        self.leader[robots[queued]] = holder[queued]
        self.ahead[winners] += 1
        self.direction[winners] = directions[wins]
        return winners

    def followable(self, keys: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Cells whose robot is already leaving them in `directions`, with nobody queued yet: a
        robot coming the same way may follow it in, never closer than touching."""
        lattice = self.lattice
        return _followable(
            keys, directions, lattice.holder, lattice.queued, self.ahead, self.direction,
            self.cell, lattice.stride,
        )  # fmt: skip

    def enterable(self, keys: np.ndarray, groups: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Cells a robot of `groups` coming in `directions` may claim: free or followable, and
        not another group's target."""
        passable = (self.lattice.holder[keys] == FREE) | self.followable(keys, directions)
        return passable & self.lattice.allows(keys, groups)

    def _move(self) -> None:
        """Advance every robot along its reserved run (see `motion.move`); a robot reaching the
        next centre gives up the cell behind it, to the robot queued for it if there is one."""
        limits, lattice = self.params.limits, self.lattice
        move(
            self.cell, self.direction, self.ahead, self.offset, self.speed, self.distance,
            self.pace, self.leader, lattice.holder, lattice.queued, lattice.stride,
            limits.max_speed, limits.max_accel,
        )  # fmt: skip

    def _audit(self) -> None:
        """Count overlapping pairs of squares, seeds included, from the positions alone."""
        world = self.world
        present = self.state != LOST
        i, j = self._auditor.pairs(
            self.cell, self.direction, self.offset, world.seeds, present, self._scratch
        )
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
        for g, at in enumerate(self.completed_at):
            if at is None and self._whole(g):
                self.completed_at[g] = self.step_count
                self.driver.completed(g)

    # --- changing the shape while it runs -------------------------------------------------------

    def reshape(self, group: int, shape: Shape, pose: Pose | None = None) -> None:
        """Form a new shape for `group` without a restart (the live editor's hand-over).

        Robots on cells that stay in the shape keep them and do not move; robots whose cells
        or targets went away wander; the strategy then hands out the open cells. A shape with
        more cells than the group's robots that can move (`movable`) can fill is refused, and
        nothing changes: it would never form (`Shape.fitted` makes one that fits).
        """
        old = self.world
        new = old.reshaped(group, shape, pose or old.groups[group].pose)
        seeds = new.mask(new.seeds) & ~old.mask(old.seeds)
        if (self.lattice.grid[seeds] >= 0).any():
            raise WorldError("the seeds' new cells are taken by robots; move them elsewhere")
        cells = new.groups[group].targets
        fillable = int(self._reachable(group)[cells[:, 0], cells[:, 1]].sum())
        movable = self.movable(group)
        if fillable > movable:
            raise WorldError(
                f"group {new.groups[group].name!r}: the new shape has {fillable:,} cells for the "
                f"{movable:,} robots that can move: short by {fillable - movable:,}; draw fewer "
                f"cells, or fit it with shape.fitted({movable})"
            )
        with self._code.running(f" as the shape changed at step {self.step_count}"):
            self.filled = np.zeros(len(new.targets), dtype=bool)
            self.driver.reshaped(_renumbering(old.targets, new.targets, new.size))
            self.lattice.grid[old.mask(old.seeds)] = FREE
            self.world = new
            self._index_world()
            self._refill()
            self.completed_at[group] = None
            self.driver.hand_out(group)

    # --- faults ---------------------------------------------------------------------------------

    def _strike(self) -> None:
        """What the fault schedule holds for this step, then the failure rate."""
        for event in self.faults.due(self.step_count):
            self.fail(event.robots(self.state, self.cell, self.rng), event.kind)
        hits = self.faults.rate_hits(self.state, self.rng)
        if len(hits):
            self.fail(hits, "remove", label="rate")

    def fail(self, robots: np.ndarray, kind: str = "remove", label: str | None = None) -> None:
        """A fault strikes `robots` now: ``remove`` takes them out of the run, ``stall`` stops
        them for good where they stand (see `swarmshape.core.faults`). The targets they had
        filled open up, the driver forgets them and refills the gaps (with ``on_loss =
        "rescale"``, a group left with fewer robots than cells it can fill is re-formed at the
        largest scale its survivors can fill), and the fault goes into `faults.log` (under
        `label`, default `kind`)."""
        stall = kind == "stall"
        robots = np.unique(np.asarray(robots, dtype=np.int64))
        robots = robots[(self.state[robots] != LOST) & ~(stall & (self.state[robots] == STALLED))]
        before = float(self.filled.mean()) if len(self.filled) else 1.0
        settled = robots[self.state[robots] == SETTLED]
        targets = self.target_at[self.cell[settled, 0], self.cell[settled, 1]]
        self.filled[targets[targets >= 0]] = False
        if stall:
            self.state[robots] = STALLED
        else:
            self._take_off(robots)
        self.dead = self._find_dead()
        with self._code.running(f" after a fault at step {self.step_count}"):
            self.driver.removed(robots, stall)
        groups = np.unique(self.group[robots]).tolist()
        for g in range(len(self.world.groups)):  # a stall may wall off another group's cells
            self._rescale_if_short(g)
        for g in groups:
            if not self._whole(g):
                self.completed_at[g] = None
        self.faults.log.append(
            {
                "step": self.step_count,
                "kind": label or kind,
                "robots": len(robots),
                "coverage_before": round(before, 6),
                "coverage_after": round(float(self.filled.mean()), 6),
                "recovered_at": None,
                "recovery_steps": None,
                "scale": round(min(g.shape.scale for g in self.world.groups), 6),
            }
        )
        self.faults.note(self.step_count, self.complete)

    def _take_off(self, robots: np.ndarray) -> None:
        """Remove robots from the lattice: the cells they hold go to the robot queued behind
        them, if any, else become free; cells they were queued for forget them."""
        ahead = self.ahead[robots]
        held = [self.cell[robots] + STEPS[self.direction[robots]] * k for k in (0, 1, 2)]
        keys = self.lattice.key(np.concatenate(held))
        who = np.tile(robots, 3)
        mine = np.concatenate([np.ones(len(robots), bool), ahead >= 1, ahead >= 2])
        keys, who = keys[mine], who[mine]
        queued = self.lattice.queued[keys] == who
        self.lattice.queued[keys[queued]] = FREE
        holds = self.lattice.holder[keys] == who
        self.leader[self.lattice.leave(keys[holds])] = -1
        self.state[robots] = LOST
        self.faults.lost_at[robots] = self.step_count
        self.leader[robots] = -1
        self.ahead[robots] = 0
        self.offset[robots] = 0.0
        self.speed[robots] = 0.0

    def _walls_moved(self, coasting: np.ndarray) -> None:
        """Stalled robots coasted on this step, so the targets they cut off may have changed:
        the driver hears of it as of their fault, and stops robots heading for a target now cut
        off and hands out one opened again. Without this a target walled off while the fault
        struck stayed open for good once the wall moved on (a star with 5 % stalled early:
        coverage 98.7 % after 5,000 steps, 31 robots idle)."""
        dead = self._find_dead()
        if np.array_equal(dead, self.dead):
            return
        self.dead = dead
        self.driver.removed(coasting, stalled=True)
        for group in range(len(self.world.groups)):
            self._rescale_if_short(group)

    def _rescale_if_short(self, group: int) -> None:
        """Too few robots left to fill the group's reachable cells, or none of them left to
        fill: form the same shape at the largest scale the survivors can fill and reach (the
        paper's answer to too few robots, live; stalled robots may wall off a small copy). If
        every copy where the shape stands is dead, the survivors form one nearby instead.
        Only when the run asks for it (``on_loss = "rescale"``): by default a shape keeps
        its size, and the cells no robot is left for stay open."""
        if self.params.on_loss != "rescale":
            return
        mobile = self.movable(group)
        shape, pose = self.world.groups[group].shape, self.world.groups[group].pose
        reachable = self._reachable(group)

        def fillable(candidate: Shape) -> int:
            cells = pose.to_world(candidate.cells)
            return int(reachable[cells[:, 0], cells[:, 1]].sum())

        if mobile < 1 or 1 <= fillable(shape) <= mobile:
            return
        smaller = next((s for s in shape.shrunk() if 1 <= fillable(s) <= mobile), None)
        if smaller is None:
            smaller = self._moved_copy(group, mobile, reachable)
        if smaller is not None:
            self.reshape(group, smaller)

    def _moved_copy(self, group: int, mobile: int, reachable: np.ndarray) -> Shape | None:
        """The largest copy of the group's shape with at most `mobile` cells that fits, every
        cell reachable and off the other groups' shapes, somewhere in the arena, at the place
        nearest where it stands (by how far its origin moves, ties to the least frame y, then
        x); None if there is no such place. Without it, robots stalled on (or walling off) every
        copy at the seeds leave a shape that never forms, with robots that can still move."""
        from scipy import signal  # only here: it costs half a second to import

        shape, pose = self.world.groups[group].shape, self.world.groups[group].pose
        width, height = self.world.size
        owner = self.lattice.owner.reshape(width + 2, height + 2)[1:-1, 1:-1]
        room = (reachable & ((owner < 0) | (owner == group))).astype(np.int64)
        if not room.any():
            return None
        for copy in (shape, *shape.shrunk()):
            if copy.count > mobile:
                continue
            cells = pose.to_world(copy.cells)
            low = cells.min(axis=0)
            footprint = np.zeros(tuple(cells.max(axis=0) - low + 1), dtype=np.int64)
            if footprint.shape[0] > width or footprint.shape[1] > height:
                continue
            footprint[cells[:, 0] - low[0], cells[:, 1] - low[1]] = 1
            # for every place of the copy's corner in the arena at once: its cells there in room
            inside = signal.correlate(room, footprint, mode="valid")
            corners = np.argwhere(inside == copy.count)
            if not len(corners):
                continue
            # the world shift, turned back into the frame (a shift is a vector: no cell rounding)
            moved = pose.to_frame(cells[0] + corners - low) - pose.to_frame(cells[:1])
            far = (moved**2).sum(axis=1)
            dx, dy = moved[np.lexsort((moved[:, 0], moved[:, 1], far))[0]]
            return replace(copy, origin=(copy.origin[0] + int(dx), copy.origin[1] + int(dy)))
        return None

    def _whole(self, group: int) -> bool:
        """Every target of `group` is filled or lost to stalled robots (see `dead`) that have
        come to rest, and not every one is lost: a shape left with no cell to fill is not
        formed. A shape that keeps its size when faults leave it short of robots
        (`Params.on_loss`) is formed as far as it can be once every robot of it that can still
        move rests on one of its targets: the cells left open wait for nobody."""
        mine = self.world.targets_of(group)
        filled, dead = self.filled[mine], self.dead[mine]
        if _first_neither(filled, dead) < 0:
            if dead.any() and not self._walls_still():
                return False  # a stalled robot still coasting may yet open a cell it cuts off
            return bool(filled.any()) or not dead.any()
        if self.params.on_loss != "keep" or not self.faults.log or not filled.any():
            return False  # only a fault (each one logged) leaves a group short of robots
        return int(filled.sum()) == self.movable(group)

    def _find_dead(self) -> np.ndarray:
        """Targets held by a stalled robot, or cut off by stalled robots (with the seeds and the
        other groups' shapes) from every robot of their group that can still move."""
        world = self.world
        dead = np.zeros(len(world.targets), dtype=bool)
        if not (self.state == STALLED).any():
            return dead
        x, y = world.targets[:, 0], world.targets[:, 1]
        for g in range(len(world.groups)):
            mine = world.target_group == g
            dead[mine] = ~self._reachable(g)[x[mine], y[mine]]
        return dead

    def _reachable(self, group: int) -> np.ndarray:
        """Per arena cell, whether a robot of `group` that can still move may get there: not
        held by a stalled robot, and not walled off by stalled robots, seeds and the other
        groups' shapes. Every cell but the seeds' while nothing has stalled."""
        grid = self.lattice.grid
        if not (self.state == STALLED).any():
            return grid != SEED
        stalled = (grid >= 0) & (self.state[np.maximum(grid, 0)] == STALLED)
        width, height = self.world.size
        owner = self.lattice.owner.reshape(width + 2, height + 2)[1:-1, 1:-1]
        passable = ~stalled & (grid != SEED) & ((owner < 0) | (owner == group))
        labels, count = scipy.ndimage.label(passable)
        cells = self.cell[self._mobile() & (self.group == group)]
        reached = np.zeros(count + 1, dtype=bool)
        reached[labels[cells[:, 0], cells[:, 1]]] = True
        reached[0] = False  # the walls
        return reached[labels]

    def _walls_still(self) -> bool:
        """No stalled robot is still coasting to its stop: the walls that decide `dead` are
        where they will stay (until another fault)."""
        return not (self.ahead[self.state == STALLED] > 0).any()

    def _mobile(self) -> np.ndarray:
        """Per robot, whether it can still move (neither lost nor stalled)."""
        return (self.state != LOST) & (self.state != STALLED)


@njit
def _first_neither(a: np.ndarray, b: np.ndarray) -> int:  # pragma: no cover (compiled)
    """The first place where neither `a` nor `b` holds, or -1: ``(a | b).all()`` without a
    pass over every target each time (a run under way has an open target early on). Checked
    four times a step; at 1,000,000 robots the masks took 1 ms each."""
    for k in range(len(a)):
        if not (a[k] or b[k]):
            return k
    return -1


@njit
def _any_able(
    state: np.ndarray, ahead: np.ndarray, group: np.ndarray, g: int
) -> bool:  # pragma: no cover (compiled)
    """Whether a robot of group `g` can still move (neither removed nor stalled) or is still
    under way, stopping at the first: in a run under way, the first robot of the group."""
    for r in range(len(state)):
        if group[r] == g and ((state[r] != LOST and state[r] != STALLED) or ahead[r] > 0):
            return True
    return False


@njit
def _followable(
    keys: np.ndarray, directions: np.ndarray, holder: np.ndarray, queued: np.ndarray,
    ahead: np.ndarray, direction: np.ndarray, cell: np.ndarray, stride: int,
) -> npt.NDArray[np.bool_]:  # pragma: no cover (compiled)  # fmt: skip
    """`Swarm.followable` over the lattice's flat arrays."""
    out = np.zeros(len(keys), dtype=np.bool_)
    for i in range(len(keys)):
        robot = holder[keys[i]]
        if robot < 0 or queued[keys[i]] != FREE:
            continue
        leaving = ahead[robot] > 0 and direction[robot] == directions[i]
        out[i] = leaving and (cell[robot, 0] + 1) * stride + cell[robot, 1] + 1 == keys[i]
    return out


def _renumbering(old: np.ndarray, new: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """For each old target, the index of the new target on the same cell, or -1."""
    index = np.full(size, -1)
    index[new[:, 0], new[:, 1]] = np.arange(len(new))
    return index[old[:, 0], old[:, 1]]

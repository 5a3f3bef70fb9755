"""Central strategies: the base class a planner subclasses, what it may see, and the driver
that brings robots to the targets it hands out.

A `Strategy` never receives the `Swarm` itself, only a `SwarmView`: the robots' cells, groups,
states and targets (read-only), the world, the run's random generator, and four actions
(`assign`, `send`, `release`, `recruit`). `Steering` is the swarm's driver for it. Each step it
turns delivered messages into assignments, picks a next cell for every mover (straight, or down
a planned path), resolves what stands in a blocked mover's way (idle robots step aside; under
`Motion.SWAP` the TSWAP rules of `swarmshape.core.tswap`), lets spare robots wander, and claims
the cells through the swarm. Robots resting on their targets settle, and the strategy hears so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from swarmshape.core.assignment import Matcher, greedy
from swarmshape.core.lattice import FREE, SEED, WALL
from swarmshape.core.messages import MessageQueue
from swarmshape.core.motion import STEPS, Motion, rows
from swarmshape.core.navigation import CrossingCounter, FieldPlanner, straight_preferences
from swarmshape.core.plugin import Plugin
from swarmshape.core.snapshot import Snapshot, decode_attributes, encode_attributes, prefixed
from swarmshape.core.states import LOST, MOVING, SETTLED, STALLED, WAITING, WANDERING
from swarmshape.core.tswap import one_per_blocker, rotate_rings, shortening_swaps

if TYPE_CHECKING:
    from swarmshape.core.messages import Message
    from swarmshape.core.swarm import Swarm
    from swarmshape.core.world import World


class Strategy(Plugin):
    """Base class of central planners: who goes to which target cell, and when.

    Subclass it, give it a ``name`` and a one-line ``description``, and hand out targets in
    `on_start`; every other hook has a default. ``motion`` declares how robots move.
    Randomness must come from ``swarm.rng`` so that runs repeat exactly per seed.
    """

    kind: ClassVar[str] = "central"
    motion: ClassVar[Motion] = Motion.SWAP

    def on_start(self, swarm: SwarmView) -> None:
        """Hand out the first targets, by ``swarm.assign`` or ``swarm.send``."""
        raise NotImplementedError(f"strategy {self.name!r} must define on_start(swarm)")

    def on_step(self, swarm: SwarmView) -> None:
        """A step begins (before robots decide where to go). Default: nothing to do."""

    def on_settled(self, swarm: SwarmView, robots: np.ndarray) -> None:
        """`robots` reached their targets this step. Default: nothing to do."""

    def on_reshape(self, swarm: SwarmView, group: int) -> None:
        """The group's shape changed while running. Default: idle robots take the open cells."""
        swarm.recruit(group)

    def on_fault(self, swarm: SwarmView, group: int, robots: np.ndarray) -> None:
        """A fault took `robots` of `group` (removed, or stalled for good): their cells are
        open again. Default: idle robots take the open cells, as after a reshape. (With
        ``on_loss = "rescale"``, a group left too short of robots is re-formed smaller
        afterwards, through `on_reshape`.)"""
        swarm.recruit(group)

    def on_renumber(self, swarm: SwarmView, renumber: np.ndarray) -> None:
        """A group's shape changed, and with it every group's target indices: ``renumber[old]``
        is each old target's new index, -1 where it went away. Keep target indices the strategy
        holds in step (they would name other cells, or none). Default: it holds none."""

    def on_hand_over(self, swarm: SwarmView, movers: np.ndarray, idle: np.ndarray) -> None:
        """Each of `idle`, boxed in a mover's way, took over that mover's target, and each of
        `movers` waits or wanders in its place. A strategy that plans ahead for waiting robots
        passes each idle robot's plan on to its mover: the idle robot is busy now, and the mover
        would otherwise never be sent. Default: it plans nothing ahead."""

    def drive(self, swarm: Swarm) -> Steering:
        return Steering(swarm, self)

    def snapshot(self) -> dict[str, Any]:
        """What a saved run keeps of this strategy. Default: every attribute but its options
        (the run keeps those), each a number, text, a numpy array, or a list of them."""
        return encode_attributes(f"strategy {self.name!r}", self._state())

    def restore(self, saved: Snapshot, swarm: SwarmView) -> None:
        """Take back what `snapshot` saved, into a freshly made strategy."""
        for name, value in decode_attributes(saved, self._state()).items():
            setattr(self, name, value)

    def _state(self) -> dict[str, Any]:
        return {name: value for name, value in vars(self).items() if name != "options"}


class SwarmView:
    """What a strategy may read and call; arrays are read-only views, indexed by robot."""

    def __init__(self, steering: Steering) -> None:
        self._steering = steering
        self._swarm = steering.swarm

    # --- reading ----------------------------------------------------------------------------

    @property
    def cells(self) -> np.ndarray:
        """Each robot's cell ``(n, 2)`` (the one it is in or leaving)."""
        return _read_only(self._swarm.cell)

    @property
    def group(self) -> np.ndarray:
        """Each robot's group index."""
        return _read_only(self._swarm.group)

    @property
    def state(self) -> np.ndarray:
        """Each robot's `swarmshape.core.states.State`."""
        return _read_only(self._swarm.state)

    @property
    def target(self) -> np.ndarray:
        """Each robot's target index into `targets`, or -1."""
        return _read_only(self._steering.target)

    @property
    def world(self) -> World:
        return self._swarm.world

    @property
    def targets(self) -> np.ndarray:
        """Every target cell ``(m, 2)``, all groups' in order."""
        return self._swarm.world.targets

    @property
    def target_group(self) -> np.ndarray:
        """The group of each target."""
        return self._swarm.world.target_group

    @property
    def rng(self) -> np.random.Generator:
        """The run's one random generator: the only source of randomness a strategy may use."""
        return self._swarm.rng

    @property
    def step(self) -> int:
        return self._swarm.step_count

    @property
    def pending(self) -> list[Message]:
        """Messages sent and not yet delivered."""
        return self._steering.queue.pending

    def waiting(self, group: int) -> np.ndarray:
        """Robots of `group` waiting for a target."""
        return self._steering.waiting(group)

    def idle(self, group: int) -> np.ndarray:
        """Robots of `group` without a task: waiting first, then wandering."""
        return self._steering.idle(group)

    def open_targets(self, group: int) -> np.ndarray:
        """Targets of `group` that nobody is settled on or heading for."""
        return self._steering.open_targets(group)

    # --- acting -----------------------------------------------------------------------------

    def assign(self, robots: np.ndarray, targets: np.ndarray) -> None:
        """Start `robots` moving to `targets` (indices into `targets`, each of the robot's own
        group) now."""
        robots = self._steering.robots(robots, "assign")
        self._steering.assign(robots, self._steering.targets_of(robots, targets, "assign"))

    def send(self, sender: int, recipient: int, target: int) -> None:
        """Message "go to `target`" to `recipient`; it arrives, and it starts, next step."""
        recipient = int(self._steering.robots(np.array([recipient]), "send")[0])
        target = int(
            self._steering.targets_of(np.array([recipient]), np.array([target]), "send")[0]
        )
        self._steering.send(sender, recipient, target)

    def release(self, robots: np.ndarray) -> None:
        """Let `robots` wander: they have nothing left to do."""
        self._steering.release(self._steering.robots(robots, "release"))

    def recruit(self, group: int, match: Matcher = greedy) -> None:
        """Match idle robots of `group` to its open targets with `match` and send them there."""
        self._steering.recruit(group, match)


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view


class Steering:
    """Targets per robot, and the rules that bring robots to them without deadlock."""

    def __init__(self, swarm: Swarm, strategy: Strategy) -> None:
        self.swarm = swarm
        self.strategy = strategy
        self.motion = strategy.motion
        n = len(swarm.cell)
        self.target = np.full(n, -1, dtype=np.int64)
        self.blocked = np.zeros(n, dtype=np.int64)
        """Steps each mover has waited behind something at rest."""
        self.routed = np.zeros(n, dtype=bool)
        """Robots that follow a planned path instead of steering straight."""
        self.recruited = np.zeros(n, dtype=bool)
        """Robots sent to a changed shape's new cells (they spare settled robots if they can)."""
        self.queue = MessageQueue()
        self.planner = FieldPlanner(swarm.world.size, n)
        self.view = SwarmView(self)

    def index_world(self) -> None:
        """What the rules derive from the world's targets (again after a reshape)."""
        self.target_mask = self.swarm.world.mask(self.swarm.world.targets)
        self._crossings = CrossingCounter(self.target_mask)
        self._open: dict[int, np.ndarray] = {}

    def start(self) -> None:
        self.strategy.on_start(self.view)

    @property
    def messages_sent(self) -> int:
        return len(self.queue.log)

    @property
    def quiet(self) -> bool:
        """A central planner never comes to rest short of its shape: its movers keep trying."""
        return False

    def figures(self) -> dict[str, Any]:
        """Nothing beyond the messages every run reports."""
        return {}

    def shown(self) -> None:
        """A central plan has nothing to show beyond where robots are going."""
        return None

    def snapshot(self) -> dict[str, Any]:
        values = {
            "target": self.target,
            "blocked": self.blocked,
            "routed": self.routed,
            "recruited": self.recruited,
        }
        values |= prefixed("queue", self.queue.snapshot())
        values |= prefixed("planner", self.planner.snapshot())
        return values | prefixed("strategy", self.strategy.snapshot())

    def restore(self, saved: Snapshot) -> None:
        swarm, n, m = self.swarm, len(self.target), len(self.swarm.world.targets)
        self.target = saved.array("target", np.int64, (n,), -1, m - 1)
        heading = self.target >= 0
        # movers and settled robots have targets, of their own group; settled ones rest on theirs
        goes = (swarm.state == MOVING) | (swarm.state == SETTLED)
        mine = swarm.world.target_group[np.maximum(self.target, 0)] == swarm.group
        settled = np.flatnonzero(swarm.state == SETTLED)
        resting = swarm.cell[settled] == swarm.world.targets[self.target[settled]]
        if (heading != goes).any() or not mine[heading].all() or not resting.all():
            raise saved.error("target", "disagrees with the robots' states, groups and cells")
        self.blocked = saved.array("blocked", np.int64, (n,), 0)
        self.routed = saved.array("routed", bool, (n,))
        self.recruited = saved.array("recruited", bool, (n,))
        self.queue = MessageQueue.restored(saved.part("queue"), n, m)
        pending = self.queue.pending
        recipients = np.array([message.recipient for message in pending], dtype=np.int64)
        targets = np.array([message.target for message in pending], dtype=np.int64)
        if (swarm.world.target_group[targets] != swarm.group[recipients]).any():
            raise saved.error("queue.pending", "sends a robot to another group's target")
        self.planner.restore(saved.part("planner"))
        self.strategy.restore(saved.part("strategy"), self.view)

    # --- what strategies call, through their view ---------------------------------------------

    def robots(self, robots: np.ndarray, action: str) -> np.ndarray:
        """`robots` as robot numbers, or an error that says which one does not exist (numpy
        would take -1 for the last robot, and fail on 10**6 deep inside a step)."""
        robots = np.asarray(robots)
        n = len(self.target)
        if robots.dtype.kind not in "iu" and robots.size:
            raise TypeError(f"{action}: robots are whole numbers, got {robots.dtype} values")
        robots = robots.astype(np.int64).reshape(-1)
        wrong = robots[(robots < 0) | (robots >= n)]
        if len(wrong):
            raise IndexError(f"{action}: there is no robot {wrong[0]} (they are 0 to {n - 1})")
        return robots

    def targets_of(self, robots: np.ndarray, targets: np.ndarray, action: str) -> np.ndarray:
        """`targets`, one per robot (or one for all), each a target of its robot's own group,
        or an error that says which is not."""
        targets = np.asarray(targets)
        m = len(self.swarm.world.targets)
        if targets.dtype.kind not in "iu" and targets.size:
            raise TypeError(f"{action}: targets are whole numbers, got {targets.dtype} values")
        try:
            targets = np.broadcast_to(targets.astype(np.int64), robots.shape)
        except ValueError:
            raise ValueError(f"{action}: {targets.size} targets for {len(robots)} robots") from None
        wrong = targets[(targets < 0) | (targets >= m)]
        if len(wrong):
            raise IndexError(f"{action}: there is no target {wrong[0]} (they are 0 to {m - 1})")
        group = self.swarm.group[robots]
        foreign = np.flatnonzero(self.swarm.world.target_group[targets] != group)
        if len(foreign):
            robot, target = robots[foreign[0]], targets[foreign[0]]
            owner = self.swarm.world.target_group[target]
            raise ValueError(
                f"{action}: target {target} belongs to group {owner} and robot {robot} to group "
                f"{group[foreign[0]]}"
            )
        return targets

    def send(self, sender: int, recipient: int, target: int) -> None:
        self.queue.send(self.swarm.step_count, sender, recipient, target)

    def assign(self, robots: np.ndarray, targets: np.ndarray) -> None:
        """Robots a fault took are skipped; a settled robot sent on leaves its target open."""
        state = self.swarm.state[robots]
        if ((state == LOST) | (state == STALLED)).any():
            working = (state != LOST) & (state != STALLED)
            robots, targets = robots[working], np.broadcast_to(targets, robots.shape)[working]
        self.swarm.dispatch(robots)
        self.target[robots] = targets
        self.blocked[robots] = 0
        self.routed[robots] = self.motion is Motion.ROUTE
        self.recruited[robots] = False
        self.planner.forget(robots)

    def release(self, robots: np.ndarray) -> None:
        self.swarm.release(robots)
        self.target[robots] = -1
        self.planner.forget(robots)

    def waiting(self, group: int) -> np.ndarray:
        swarm = self.swarm
        return np.flatnonzero((swarm.state == WAITING) & (swarm.group == group))

    def idle(self, group: int) -> np.ndarray:
        swarm = self.swarm
        mine = swarm.group == group
        return np.concatenate(
            [np.flatnonzero(mine & (swarm.state == state)) for state in (WAITING, WANDERING)]
        )

    def open_targets(self, group: int) -> np.ndarray:
        taken = np.zeros(len(self.swarm.filled), dtype=bool)
        taken[self.target[self.target >= 0]] = True
        taken |= self.swarm.dead
        return np.flatnonzero((self.swarm.world.target_group == group) & ~taken)

    def recruit(self, group: int, match: Matcher = greedy) -> None:
        """Recruits plan paths around settled robots when they can, so robots that already
        hold their cells stay put; only a cell walled in by settled robots makes them swap."""
        targets, robots = self.open_targets(group), self.idle(group)
        if len(targets) == 0 or len(robots) == 0:
            return
        swarm = self.swarm
        goals, cells = swarm.world.targets[targets].astype(float), swarm.cell[robots].astype(float)
        if len(robots) >= len(targets):
            self.assign(robots[match(cells, goals, swarm.rng)], targets)
        else:  # too few robots: each robot takes a target, the rest stay open
            self.assign(robots, targets[match(goals, cells, swarm.rng)])
        self.routed[robots] = True
        self.recruited[robots] = True

    # --- the swarm's calls ----------------------------------------------------------------------

    def decide(self) -> None:
        """Every robot that wants a next cell claims it through the swarm."""
        self.strategy.on_step(self.view)
        self._deliver_messages()
        starters, cruisers, stuck = self._who_moves()
        self._plan(starters[self.routed[starters]])
        movers = np.concatenate([starters, cruisers])
        steps = self._next_cells(movers, len(starters))
        pushed = self._make_way(steps.blocked, steps.blocker)
        steppers = np.unique(np.concatenate([pushed, self._roaming()]))
        robots = np.concatenate([movers[steps.may], steppers, stuck])
        directions = np.concatenate(
            [
                steps.chosen[steps.may],
                self._random_free_step(steppers, own_shape_too=True),
                self._random_free_step(stuck, own_shape_too=False),
            ]
        )
        lattice, cell = self.swarm.lattice, self.swarm.cell
        origins = np.concatenate(
            [
                steps.origin_key[steps.may],
                lattice.key(rows(cell, steppers)),
                lattice.key(rows(cell, stuck)),
            ]
        )
        winners = self.swarm.claim(robots, directions, origins)
        self._count_waiting(starters, stuck, steps, winners)

    def arrived(self) -> None:
        """Moving robots resting on their own target settle there; the strategy hears of it."""
        swarm = self.swarm
        candidates = np.flatnonzero((swarm.state == MOVING) & (swarm.ahead == 0))
        apart = rows(swarm.cell, candidates) - rows(swarm.world.targets, self.target[candidates])
        done = candidates[(apart[:, 0] == 0) & (apart[:, 1] == 0)]
        swarm.settle(done)
        self.routed[done] = False  # the way it went round something is behind it
        self.planner.forget(done)
        if len(done):
            self.strategy.on_settled(self.view, done)

    def completed(self, group: int) -> None:
        """A group's shape is complete: its robots still waiting are spare and may wander."""
        self.release(self.waiting(group))

    def reshaped(self, renumber: np.ndarray) -> None:
        """The targets were renumbered (-1: gone); robots whose target went away wander."""
        self.queue.retarget(renumber)
        has_target = self.target >= 0
        self.target[has_target] = renumber[self.target[has_target]]
        self.release(np.flatnonzero(has_target & (self.target < 0)))
        self.strategy.on_renumber(self.view, renumber)

    def removed(self, robots: np.ndarray, stalled: bool) -> None:
        """A fault took `robots`: forget their targets, paths and messages; robots heading for a
        target that a stall made unreachable wait again; the strategy refills each group."""
        swarm = self.swarm
        self.target[robots] = -1
        self.blocked[robots] = 0
        self.routed[robots] = False
        self.recruited[robots] = False
        self.planner.forget(robots)
        self.queue.drop(robots)
        heading = np.flatnonzero(self.target >= 0)
        doomed = heading[swarm.dead[self.target[heading]]]
        swarm.wait(doomed)
        self.target[doomed] = -1
        self.planner.forget(doomed)
        if stalled:  # everyone plans afresh around the new obstacles
            self.planner.forget(np.arange(len(self.target)))
        for group in np.unique(swarm.group[robots]).tolist():
            self.strategy.on_fault(self.view, group, robots[swarm.group[robots] == group])

    def hand_out(self, group: int) -> None:
        """After a reshape: everyone plans afresh, and the strategy hands out the open cells."""
        self.planner.forget(np.arange(len(self.target)))
        self.strategy.on_reshape(self.view, group)

    # --- one step, phase by phase ---------------------------------------------------------------

    def _deliver_messages(self) -> None:
        for message in self.queue.deliver():
            self.assign(np.array([message.recipient]), np.array([message.target]))

    def _who_moves(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Movers at rest (starters), movers under way (cruisers), and long-blocked movers that
        sidestep instead, each with even odds per step so that two robots stuck on each other
        do not dodge in lockstep."""
        swarm = self.swarm
        moving = swarm.state == MOVING
        starters = np.flatnonzero(moving & (swarm.ahead == 0))
        stuck = starters[self.blocked[starters] >= 2 * self.swarm.params.patience]
        if len(stuck):
            stuck = stuck[swarm.rng.random(len(stuck)) < 0.5]
            starters = np.setdiff1d(starters, stuck, assume_unique=True)
        cruisers = np.flatnonzero(moving & (swarm.ahead == 1))
        return starters, cruisers, stuck

    def _next_cells(self, movers: np.ndarray, starters: int) -> _Steps:
        """Each mover's next cell: its first choice if enterable, else (for starters) its second;
        cruisers may only extend their run straight on. Starters that cannot go are blocked."""
        swarm, lattice = self.swarm, self.swarm.lattice
        along = rows(STEPS, swarm.direction[movers]) * swarm.ahead[movers, None]
        origin = rows(swarm.cell, movers) + along
        first, second = self._preferences(movers, origin)
        origin_key = lattice.key(origin)
        groups = swarm.group[movers]
        first_free = swarm.enterable(origin_key + lattice.offsets[first], groups, first)
        second_free = swarm.enterable(origin_key + lattice.offsets[second], groups, second)
        is_starter = np.arange(len(movers)) < starters
        use_second = ~first_free & second_free & (second > 0) & is_starter
        chosen = np.where(use_second, second, first)
        may = (chosen > 0) & (first_free | use_second)
        may &= is_starter | (chosen == swarm.direction[movers])

        waiting = ~may[:starters]
        blocked, blocked_first = movers[:starters][waiting], first[:starters][waiting]
        blocked_at = origin_key[:starters][waiting] + lattice.offsets[blocked_first]
        owner = lattice.owner[blocked_at]
        foreign = (owner >= 0) & (owner != swarm.group[blocked])
        blocker = np.where((blocked_first > 0) & ~foreign, lattice.holder[blocked_at], WALL)
        return _Steps(chosen, may, origin_key, blocked, blocker)

    def _preferences(self, movers: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each mover's preferred and second-best direction (0 for none)."""
        swarm = self.swarm
        goals = swarm.world.targets[self.target[movers]]
        first, second = straight_preferences(
            origin, goals, swarm.direction[movers], self._crossings
        )
        routed = self.routed[movers]
        if routed.any():
            first[routed] = self.planner.directions(
                movers[routed], origin[routed], goals[routed], swarm.direction[movers[routed]]
            )
            second[routed] = 0
        return first, second

    def _make_way(self, blocked: np.ndarray, blocker: np.ndarray) -> np.ndarray:
        """Resolve what stands in blocked movers' way; return idle robots asked to step aside.

        Idle robots (waiting or wandering, at rest) step aside. One that cannot, caught inside
        its own shape or in a pocket of it with no free cell to step to, takes the mover's
        target instead (`_hand_over`): under every motion, or a wanderer left in a hole of a
        shape re-formed smaller blocks the paper's one mover for ever. One of another group
        with no free cell, waited on for `patience` steps, cannot take the target: the mover
        passes it to a settled robot of its own group beside it, nearer the target
        (`_pass_to_settled_nearer`). Under `Motion.SWAP` a ring of
        resting movers each waiting for the next passes its targets round; two movers trade
        targets when that shortens their trips (`_trips`); a settled robot of the same group
        swaps targets with the mover; no robot takes part in two of these in one step; and a
        seed, a stalled robot or another group's settled robot makes the mover plan a path
        around it.
        """
        swarm = self.swarm
        robot = np.maximum(blocker, 0)
        is_robot = blocker >= 0
        state = swarm.state[robot]
        at_rest = swarm.ahead[robot] == 0
        idle = is_robot & at_rest & ((state == WAITING) | (state == WANDERING))
        same_group = is_robot & (swarm.group[robot] == swarm.group[blocked])
        boxed = ~self._free_steps(robot, own_shape_too=True).any(1)
        caught = idle & same_group & (self._in_own_shape(robot) | boxed)
        # a wanderer of one group in a dead end of another's shape, the mover behind it its only
        # way out, and nothing else leading to the open cell: two random shapes under `paper`
        walled = idle & ~same_group & boxed
        walled &= self.blocked[blocked] >= swarm.params.patience
        if caught.any() or walled.any():
            self._hand_over(*one_per_blocker(blocked[caught], robot[caught]))
            passed_to = self._pass_to_settled_nearer(blocked[walled])
            rest = ~caught & ~walled & ~np.isin(blocker, passed_to)
            return self._make_way(blocked[rest], blocker[rest])
        if self.motion is Motion.ROUTE:
            return blocker[idle]
        settled = is_robot & (state == SETTLED)
        waits_for_mover = same_group & at_rest & (state == MOVING)
        givers, receivers = rotate_rings(blocked[waits_for_mover], robot[waits_for_mover])
        # Their waiting time keeps counting: two movers that steered different ways round an
        # obstacle could trade targets back and forth for ever, and this way they sidestep.
        self._pass_targets(givers, receivers)
        traded = np.zeros(len(self.target), dtype=bool)
        traded[receivers] = True
        tangled = waits_for_mover & ~traded[blocked] & ~traded[robot]
        a, b = shortening_swaps(blocked[tangled], robot[tangled], swarm.cell, self._trips)
        self._pass_targets(np.concatenate([a, b]), np.concatenate([b, a]))
        traded[a] = traded[b] = True
        # a mover whose target just changed was blocked on the way to the old one: swapping
        # that one on to a settled robot sent three robots round a loop of trades for good
        swap = settled & same_group & ~traded[blocked]
        self._swap_with_settled(*one_per_blocker(blocked[swap], robot[swap]))
        stalled = is_robot & (state == STALLED)
        fixed = (blocker == SEED) | (blocker == WALL) | (settled & ~same_group) | stalled
        self.routed[blocked[fixed]] = True
        return blocker[idle]

    def _pass_to_settled_nearer(self, movers: np.ndarray) -> np.ndarray:
        """Each mover swaps targets with the settled robot of its group beside it that is
        nearest the mover's target, if one is nearer than the mover; return those robots. The
        settled robot steps on toward the target and the mover into its cell; as with a
        hand-over, the robot heading for the target is nearer it after each pass, so passes
        cannot go on for ever."""
        swarm, lattice = self.swarm, self.swarm.lattice
        here = lattice.key(rows(swarm.cell, movers))
        holder = lattice.holder[here[:, None] + lattice.offsets[1:]]
        beside = np.maximum(holder, 0)
        goal = rows(swarm.world.targets, self.target[movers])
        gap = np.abs(swarm.cell[beside] - goal[:, None]).sum(-1)
        nearer = gap < np.abs(rows(swarm.cell, movers) - goal).sum(-1)[:, None]
        nearer &= (holder >= 0) & (swarm.state[beside] == SETTLED)
        nearer &= swarm.group[beside] == swarm.group[movers][:, None]
        best = np.argmin(np.where(nearer, gap, np.iinfo(np.int64).max), axis=1)
        has = nearer.any(axis=1)
        movers, settled = one_per_blocker(movers[has], beside[has, best[has]])
        self._swap_with_settled(movers, settled)
        return settled

    def _pass_targets(self, givers: np.ndarray, receivers: np.ndarray) -> None:
        """Receivers take over the givers' targets, all at once, and plan afresh. Whether the
        way there goes round something (`routed`) stays with each robot: passed on with the
        target in trades too, it cost the 1,000-robot star under `optimal` 194 steps to form
        against 173."""
        self.target[receivers] = self.target[givers]
        self.planner.forget(receivers)

    def _trips(self, robots: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """Steps from `cells` to each robot's target as it would go: along its field if it is
        routed round something, else lattice distance. Measured by lattice distance alone, a
        trade sent a mover round a stalled robot back the target it had just swapped on, for
        good (a square with 5 % stalled early, under `greedy`)."""
        apart = cells - rows(self.swarm.world.targets, self.target[robots])
        trips = (np.abs(apart[:, 0]) + np.abs(apart[:, 1])).astype(np.float64)
        routed = np.flatnonzero(self.routed[robots] & self.planner.planned(robots))
        trips[routed] = self.planner.remaining(robots[routed], rows(cells, routed))
        return trips

    def _in_own_shape(self, robots: np.ndarray) -> np.ndarray:
        """Whether each robot rests on a cell of its own group's shape."""
        lattice = self.swarm.lattice
        return lattice.owner[lattice.key(rows(self.swarm.cell, robots))] == self.swarm.group[robots]

    def _hand_over(self, movers: np.ndarray, idle: np.ndarray) -> None:
        """An idle robot caught inside its shape, in a mover's way, takes the mover's target,
        and the mover waits or wanders in its place, as it did. Among movers and settled robots
        the idle robot finds no free cell to step aside into: a block with 5 % stalled early,
        under `random`, jammed at 48 % behind such wanderers, and two random shapes under
        `random` never formed behind a spare one still waiting, every target handed out
        (`scripts/faults.py --heal`). The idle robot stands one cell further along the mover's
        way, so every hand-over shortens the trips left and they cannot go on for ever; the
        mover it replaces may be in the next mover's way in turn, and so on out. The idle robot
        goes on round whatever the mover was going round, as after a swap. Whatever the
        strategy still plans for the idle robot passes to the mover (`Strategy.on_hand_over`)."""
        waited = self.swarm.state[idle] == WAITING
        self.assign(idle, self.target[movers])
        self.routed[idle] = self.routed[movers]
        self.release(movers)
        self.swarm.wait(movers[waited])
        self.strategy.on_hand_over(self.view, movers, idle)

    def _swap_with_settled(self, movers: np.ndarray, settled: np.ndarray) -> None:
        """The settled robot takes the mover's target and moves on; the mover takes its cell."""
        self.swarm.dispatch(settled)
        both = np.concatenate([movers, settled])
        self._pass_targets(both, np.concatenate([settled, movers]))
        # the pushed robot goes on round what the mover was going round (a settled robot has
        # no way to go): going straight for the target it stepped back into the mover, and as
        # a ring of two they passed the target back and forth (a ring, 5 % stalled early)
        self.routed[both] = self.routed[np.concatenate([settled, movers])]
        self.blocked[both] = 0
        # a swap passes the trip on through settled robots: going round them now would turn
        # the pushed robot back into the mover, which swaps it back in, for ever
        self.recruited[both] = False

    def _roaming(self) -> np.ndarray:
        """Wanderers at rest that try a random step this step."""
        swarm = self.swarm
        return np.flatnonzero(
            (swarm.state == WANDERING)
            & (swarm.ahead == 0)
            & (swarm.rng.random(len(swarm.state)) < self.swarm.params.wander_rate)
        )

    def _random_free_step(self, robots: np.ndarray, *, own_shape_too: bool) -> np.ndarray:
        """A random direction to an enterable neighbour cell (0 where there is none), of
        `_free_steps`."""
        if len(robots) == 0:
            return np.zeros(0, dtype=np.int64)
        ok = self._free_steps(robots, own_shape_too=own_shape_too)
        score = np.where(ok, self.swarm.rng.random((len(robots), 4)), -1.0)
        best = np.argmax(score, axis=1)
        return np.where(score.max(axis=1) >= 0, best + 1, 0)

    def _free_steps(self, robots: np.ndarray, *, own_shape_too: bool) -> np.ndarray:
        """Per robot ``(k, 4)``, which neighbour cells (by `STEPS` direction 1 to 4) an idle robot
        may step into: free, and out of every shape (its own group's too, with `own_shape_too`)
        unless a new shape was drawn over it, which it must be able to walk out of."""
        swarm, lattice = self.swarm, self.swarm.lattice
        here = lattice.key(rows(swarm.cell, robots))
        near = here[:, None] + lattice.offsets[None, 1:]
        groups = np.full(len(robots), -1) if own_shape_too else swarm.group[robots]
        ok = lattice.enterable(near, groups[:, None])
        caught = np.flatnonzero(own_shape_too & (lattice.owner[here] >= 0))
        ok[caught] = lattice.holder[near[caught]] == FREE
        return ok

    def _count_waiting(
        self, starters: np.ndarray, stuck: np.ndarray, steps: _Steps, winners: np.ndarray
    ) -> None:
        """Moving on resets a mover's wait; waiting behind something at rest adds to it, and
        as the wait reaches `patience` steps the mover plans afresh. Of two movers in each
        other's way that would plan afresh in the same step, only the lower-numbered one does,
        and the other keeps its way: planning together, each went round the other side by
        side, met again, and so for good (the paper's movers of two groups passing)."""
        swarm = self.swarm
        moved = np.zeros(len(swarm.state), dtype=bool)
        moved[winners] = True
        self.blocked[stuck] = 0
        self.blocked[starters[moved[starters]]] = 0
        robot = np.maximum(steps.blocker, 0)
        at_rest = (steps.blocker < 0) | (swarm.ahead[robot] == 0)
        waited = steps.blocked[at_rest]
        self.blocked[waited] += 1
        # only a wait that reaches patience now: the mover of a pair that kept its way stays at
        # patience while the other moves off, and planning then, round the other's old cell,
        # it went the same way round and met it again, for good (paper, two random shapes)
        replan = waited[self.blocked[waited] == self.swarm.params.patience]
        waits_for = np.full(len(swarm.state), -1, dtype=np.int64)
        waits_for[steps.blocked] = steps.blocker
        other = waits_for[replan]
        both = np.zeros(len(swarm.state), dtype=bool)
        both[replan] = True
        mutual = (other >= 0) & both[np.maximum(other, 0)]
        mutual &= waits_for[np.maximum(other, 0)] == replan
        replan = replan[~mutual | (replan < other)]
        self.planner.forget(np.concatenate([replan, stuck]))

    def _plan(self, starters: np.ndarray) -> None:
        """Give each routed starter without a field one, in the strictest view that works.

        Nobody enters a seed or another group's shape. Under `Motion.ROUTE` a mover also goes
        around every robot if it can, else around resting ones, else around settled ones only.
        Under `Motion.SWAP` movers swap their way through settled robots; recruits of a changed
        shape first try to go around them, so that robots on kept cells stay put.
        """
        needing = starters[~self.planner.planned(starters)].tolist()
        if not needing:
            return
        swarm = self.swarm
        holder = swarm.lattice.grid
        robot_here = holder >= 0
        # the robots' states cell by cell, only when a view needs them (a whole-arena gather)
        stalls = bool((swarm.state == STALLED).any())
        wanted = stalls or self.motion is Motion.ROUTE or bool(self.recruited[needing].any())
        state = np.where(robot_here, swarm.state[np.maximum(holder, 0)], -1) if wanted else None
        for group in np.unique(swarm.group[needing]).tolist():
            unfixed = self._unfixed(group) & (state != STALLED) if stalls else self._unfixed(group)
            if self.motion is Motion.ROUTE:
                resting = robot_here & (state != MOVING)
                views = [unfixed & ~robot_here, unfixed & ~resting, unfixed & (state != SETTLED)]
            else:
                views = [unfixed & (state != SETTLED) if wanted else None, unfixed]
            for agent in [a for a in needing if swarm.group[a] == group]:
                own = views if self.motion is Motion.ROUTE or self.recruited[agent] else views[1:]
                x, y = swarm.cell[agent]
                was = [view[x, y] for view in own]
                for view in own:  # its own cell is open to it (put back after)
                    view[x, y] = True
                goal = swarm.world.targets[self.target[agent]]
                self.planner.plan(agent, swarm.cell[agent], goal, own)
                for view, value in zip(own, was, strict=True):
                    view[x, y] = value

    def _unfixed(self, group: int) -> np.ndarray:
        """Cells not closed to `group` for good: neither a seed nor another group's shape (kept
        until the world changes; a planner may open a cell in it and close it again)."""
        if group not in self._open:
            lattice, (width, height) = self.swarm.lattice, self.swarm.world.size
            owner = lattice.owner.reshape(width + 2, height + 2)[1:-1, 1:-1]
            self._open[group] = ~((lattice.grid == SEED) | ((owner >= 0) & (owner != group)))
        return self._open[group]


@dataclass(frozen=True)
class _Steps:
    """The movers' choices in one step: direction, whether it may be claimed, where from; and
    the starters that could not go, with what blocks each (a robot index or a holder code)."""

    chosen: np.ndarray
    may: np.ndarray
    origin_key: np.ndarray
    blocked: np.ndarray
    blocker: np.ndarray

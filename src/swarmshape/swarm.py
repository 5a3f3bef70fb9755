"""`Swarm`: every agent's state as numpy arrays, advanced one step at a time.

All agents run one program, expressed as a state per agent and advanced in bulk with masks:
waiting (for a message), moving (to a target), settled (on it, for good), wandering (a spare
agent walking at random outside the shape). A strategy plug-in decides who goes where; this
module moves agents there without collisions. The core never imports pygame.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import TYPE_CHECKING

import numpy as np

from swarmshape.assignment import Matcher, greedy
from swarmshape.messages import MessageQueue
from swarmshape.motion import (
    FREE,
    SEED,
    STEPS,
    TOUCH,
    WALL,
    Limits,
    advance,
    overlapping_pairs,
    positions,
    resolve_claims,
)
from swarmshape.navigation import CrossingCounter, FieldPlanner, straight_preferences
from swarmshape.world import WorldError

if TYPE_CHECKING:
    from swarmshape.shape import Pose, Shape
    from swarmshape.strategies import Strategy
    from swarmshape.world import World


class State(IntEnum):
    WAITING = 0
    MOVING = 1
    SETTLED = 2
    WANDERING = 3


WAITING, MOVING, SETTLED, WANDERING = (int(state) for state in State)
"""Plain ints for the hot loop: an IntEnum member lookup costs a microsecond each time."""


@dataclass(frozen=True)
class Params:
    """Behaviour knobs shared by all agents."""

    limits: Limits = field(default_factory=Limits)
    wander_rate: float = 0.1
    """Chance per step that a resting wanderer tries a random step."""
    patience: int = 3
    """Steps a mover waits behind a resting agent before it replans; twice that, it sidesteps."""


def _renumbering(old: np.ndarray, new: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """For each old target, the index of the new target on the same cell, or -1."""
    index = np.full(size, -1)
    index[new[:, 0], new[:, 1]] = np.arange(len(new))
    return index[old[:, 0], old[:, 1]]


class Swarm:
    """One run: the world, the agents' arrays, the message queue and the one random generator.

    Movers of a *concurrent* strategy steer straight for their targets and swap targets with a
    settled agent of their group that stands in the way (TSWAP, Okumura and Defago 2023), so a
    target walled in by others is passed inward instead of deadlocking; they plan a path only
    around fixed obstacles. Movers of a one-at-a-time strategy (the paper's) always plan paths.
    """

    def __init__(
        self,
        world: World,
        strategy: Strategy,
        seed: int,
        params: Params | None = None,
        start: np.ndarray | None = None,
    ) -> None:
        self.world = world
        self.strategy = strategy
        self.concurrent = bool(getattr(strategy, "concurrent", True))
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
        self.ahead = np.zeros(n, dtype=np.int64)
        self.offset = np.zeros(n)
        self.speed = np.zeros(n)
        self.distance = np.zeros(n)
        self.state = np.full(n, WAITING, dtype=np.int8)
        self.target = np.full(n, -1, dtype=np.int64)
        self.blocked = np.zeros(n, dtype=np.int64)
        self.routed = np.zeros(n, dtype=bool)
        """Agents that follow a planned path instead of steering straight."""
        self.recruited = np.zeros(n, dtype=bool)
        """Agents sent to a changed shape's new cells (they spare settled agents if they can)."""
        width, height = world.size
        self._stride = height + 2
        self._neighbour = np.array([0, self._stride, -self._stride, 1, -1])
        padded = np.full((width + 2, height + 2), WALL, dtype=np.int64)
        self.occupancy = padded[1:-1, 1:-1]
        """Per cell ``[x, y]``: the agent holding it, FREE or SEED (a view of a walled grid)."""
        self._occupancy = padded.reshape(-1)
        self.occupancy[...] = FREE
        self.occupancy[self.cell[:, 0], self.cell[:, 1]] = np.arange(n)
        self.filled = np.zeros(len(world.targets), dtype=bool)
        self.queue = MessageQueue()
        self.planner = FieldPlanner(world.size, n)
        self.step_count = 0
        self.overlap_total = 0
        self.overlaps = np.zeros(len(world.groups), dtype=np.int64)
        """Overlapping pairs summed over steps, per group (a pair counts for both its groups)."""
        self._index_world()
        self.completed_at: list[int | None] = [None] * len(world.groups)
        self.strategy.start(self)

    def _index_world(self) -> None:
        """Everything derived from the world's targets and seeds (again after a reshape)."""
        world = self.world
        self.occupancy[world.seeds[:, 0], world.seeds[:, 1]] = SEED
        self.target_mask = world.mask(world.targets)
        owner = np.full(world.size, -1)
        owner[world.targets[:, 0], world.targets[:, 1]] = world.target_group
        self._owner = np.pad(owner, 1, constant_values=-1).reshape(-1)
        """Per walled-grid key: the group whose target is there, or -1."""
        self._targets_per_group = np.array([len(g.targets) for g in world.groups])
        self._crossings = CrossingCounter(self.target_mask)
        seeds_per_group = [len(g.seeds) for g in world.groups]
        self._seed_group = np.repeat(np.arange(len(world.groups)), seeds_per_group)
        self._seed_keys = self._key(world.seeds)
        self._seed_ids = len(self.cell) + np.arange(len(world.seeds))

    # --- what strategies call -------------------------------------------------------------

    def send(self, sender: int, recipient: int, target: int) -> None:
        """Queue the message "go to `target`" for `recipient`; it arrives next step."""
        self.queue.send(self.step_count, sender, recipient, target)

    def assign(self, agents: np.ndarray, targets: np.ndarray) -> None:
        """Start `agents` moving to `targets` (indices into ``world.targets``)."""
        self.state[agents] = MOVING
        self.target[agents] = targets
        self.blocked[agents] = 0
        self.routed[agents] = not self.concurrent
        self.recruited[agents] = False
        self.planner.forget(agents)

    def release(self, agents: np.ndarray) -> None:
        """Let `agents` wander: they have nothing left to do."""
        self.state[agents] = WANDERING
        self.target[agents] = -1
        self.planner.forget(agents)

    def waiting(self, group: int) -> np.ndarray:
        return np.flatnonzero((self.state == WAITING) & (self.group == group))

    def recruit(self, group: int, match: Matcher = greedy) -> None:
        """Match idle agents of `group` to its open targets and send them there.

        Recruits plan paths around settled agents when they can, so agents that already hold
        their cells stay put; only a cell walled in by settled agents makes them swap.
        """
        targets, agents = self.open_targets(group), self.idle(group)
        if len(targets) == 0 or len(agents) == 0:
            return
        goals, cells = self.world.targets[targets].astype(float), self.cell[agents].astype(float)
        if len(agents) >= len(targets):
            self.assign(agents[match(cells, goals, self.rng)], targets)
        else:  # too few agents: each agent takes a target, the rest stay open
            self.assign(agents, targets[match(goals, cells, self.rng)])
        self.routed[agents] = True
        self.recruited[agents] = True

    def open_targets(self, group: int) -> np.ndarray:
        """Targets of `group` that nobody is settled on or heading for."""
        taken = np.zeros(len(self.filled), dtype=bool)
        taken[self.target[self.target >= 0]] = True
        return np.flatnonzero((self.world.target_group == group) & ~taken)

    def idle(self, group: int) -> np.ndarray:
        """Agents of `group` without a task: waiting first, then wandering."""
        mine = self.group == group
        return np.concatenate(
            [np.flatnonzero(mine & (self.state == state)) for state in (WAITING, WANDERING)]
        )

    # --- reading the run ------------------------------------------------------------------

    @property
    def complete(self) -> bool:
        return bool(self.filled.all())

    def positions(self) -> np.ndarray:
        """Agent square centres ``(n, 2)`` in world units."""
        return positions(self.cell, self.direction, self.offset)

    def cells_under(self) -> np.ndarray:
        """The cell under each agent's centre ``(n, 2)``."""
        return np.floor(self.positions()).astype(np.int64)

    # --- changing the shape while it runs -----------------------------------------------

    def reshape(self, group: int, shape: Shape, pose: Pose | None = None) -> None:
        """Form a new shape for `group` without a restart (the live editor's hand-over).

        Agents on cells that stay in the shape keep them and do not move; agents whose cells
        or targets went away wander; the strategy then hands out the open cells.
        """
        old = self.world
        new = old.reshaped(group, shape, pose or old.groups[group].pose)
        seeds = new.mask(new.seeds) & ~old.mask(old.seeds)
        if (self.occupancy[seeds] >= 0).any():
            raise WorldError("the seeds' new cells are taken by robots; move them elsewhere")
        renumber = _renumbering(old.targets, new.targets, new.size)
        self.queue.retarget(renumber)
        has_target = self.target >= 0
        self.target[has_target] = renumber[self.target[has_target]]
        lost = has_target & (self.target < 0)
        self.release(np.flatnonzero(lost))
        self.filled = np.zeros(len(new.targets), dtype=bool)
        self.filled[self.target[self.state == SETTLED]] = True
        self.occupancy[old.mask(old.seeds)] = FREE
        self.world = new
        self._index_world()
        self.completed_at[group] = None
        self.planner.forget(np.arange(len(self.cell)))
        hand_out = getattr(self.strategy, "on_reshape", None)
        if hand_out is None:
            self.recruit(group)
        else:
            hand_out(self, group)

    # --- one step -------------------------------------------------------------------------

    def step(self) -> None:
        for message in self.queue.deliver():
            self.assign(np.array([message.recipient]), np.array([message.target]))
        self._reserve()
        self._move()
        settled = self._settle()
        if len(settled):
            self.strategy.on_settled(self, settled)
        self.step_count += 1
        self._observe()

    def run(self, max_steps: int) -> None:
        """Step until every target is filled or `max_steps` steps have run in total."""
        while not self.complete and self.step_count < max_steps:
            self.step()

    def _key(self, cells: np.ndarray) -> np.ndarray:
        """Flat index into the walled occupancy grid."""
        return (cells[:, 0] + 1) * self._stride + cells[:, 1] + 1

    def _reserve(self) -> None:
        """Every agent that wants a next cell claims it; free cells go to one claimant each."""
        patience = self.params.patience
        moving = self.state == MOVING
        starters = np.flatnonzero(moving & (self.ahead == 0))
        # long-blocked movers sidestep, each with even odds per step, so two agents stuck on
        # each other do not dodge in lockstep
        stuck = starters[self.blocked[starters] >= 2 * patience]
        if len(stuck):
            stuck = stuck[self.rng.random(len(stuck)) < 0.5]
            starters = np.setdiff1d(starters, stuck, assume_unique=True)
        cruisers = np.flatnonzero(moving & (self.ahead == 1))
        self._plan(starters[self.routed[starters]])
        movers = np.concatenate([starters, cruisers])
        origin = self.cell[movers] + STEPS[self.direction[movers]] * self.ahead[movers, None]
        first, second = self._preferences(movers, origin)
        origin_key = self._key(origin)
        groups = self.group[movers]
        first_free = self._enterable(origin_key + self._neighbour[first], groups)
        second_free = self._enterable(origin_key + self._neighbour[second], groups)
        is_starter = np.arange(len(movers)) < len(starters)
        use_second = ~first_free & second_free & (second > 0) & is_starter
        chosen = np.where(use_second, second, first)
        may = (chosen > 0) & (first_free | use_second)
        may &= is_starter | (chosen == self.direction[movers])

        waiting_starters = ~may[: len(starters)]
        blocked, blocked_first = (
            starters[waiting_starters],
            first[: len(starters)][waiting_starters],
        )
        blocked_at = origin_key[: len(starters)][waiting_starters] + self._neighbour[blocked_first]
        foreign = self._owner[blocked_at] >= 0
        foreign &= self._owner[blocked_at] != self.group[blocked]
        blocker = np.where((blocked_first > 0) & ~foreign, self._occupancy[blocked_at], WALL)
        pushed = self._make_way(blocked, blocker)

        roaming = np.flatnonzero(
            (self.state == WANDERING)
            & (self.ahead == 0)
            & (self.rng.random(len(self.state)) < self.params.wander_rate)
        )
        steppers = np.unique(np.concatenate([pushed, roaming]))
        agents = np.concatenate([movers[may], steppers, stuck])
        dirs = np.concatenate(
            [
                chosen[may],
                self._random_free_step(steppers, own_shape_too=True),
                self._random_free_step(stuck, own_shape_too=False),
            ]
        )
        froms = np.concatenate(
            [origin_key[may], self._key(self.cell[steppers]), self._key(self.cell[stuck])]
        )
        claim = dirs > 0
        agents, dirs, keys = agents[claim], dirs[claim], froms[claim] + self._neighbour[dirs[claim]]
        wins = self._occupancy[keys] == FREE
        wins[wins] = resolve_claims(keys[wins], self.rng)
        winners = agents[wins]
        self._occupancy[keys[wins]] = winners
        self.ahead[winners] += 1
        self.direction[winners] = dirs[wins]

        moved = np.zeros(len(self.state), dtype=bool)
        moved[winners] = True
        self.blocked[stuck] = 0
        self.blocked[starters[moved[starters]]] = 0
        self.blocked[blocked[self._counts_as_waiting(blocker)]] += 1
        replan = starters[self.blocked[starters] == patience]
        self.planner.forget(np.concatenate([replan, stuck]))

    def _preferences(self, movers: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each mover's preferred and second-best direction (0 for none)."""
        goals = self.world.targets[self.target[movers]]
        first, second = straight_preferences(origin, goals, self.direction[movers], self._crossings)
        routed = self.routed[movers]
        if routed.any():
            first[routed] = self.planner.directions(
                movers[routed], origin[routed], goals[routed], self.direction[movers[routed]]
            )
            second[routed] = 0
        return first, second

    def _make_way(self, blocked: np.ndarray, blocker: np.ndarray) -> np.ndarray:
        """Resolve what stands in blocked movers' way; return idle agents asked to step aside.

        Idle agents (waiting or wandering, at rest) step aside. In concurrent mode a settled
        agent of the same group swaps targets with the mover, a ring of resting movers each
        waiting for the next rotates its targets, and a seed or another group's settled agent
        makes the mover plan a path around it.
        """
        agent = np.maximum(blocker, 0)
        is_agent = blocker >= 0
        state = self.state[agent]
        at_rest = self.ahead[agent] == 0
        idle = is_agent & at_rest & ((state == WAITING) | (state == WANDERING))
        if not self.concurrent:
            return blocker[idle]
        same_group = is_agent & (self.group[agent] == self.group[blocked])
        settled = is_agent & (state == SETTLED)
        waits_for_mover = same_group & at_rest & (state == MOVING)
        self._rotate_rings(blocked[waits_for_mover], agent[waits_for_mover])
        swap = settled & same_group
        self._swap_with_settled(blocked[swap], agent[swap])
        fixed = (blocker == SEED) | (blocker == WALL) | (settled & ~same_group)
        self.routed[blocked[fixed]] = True
        return blocker[idle]

    def _rotate_rings(self, waiting: np.ndarray, waited_for: np.ndarray) -> None:
        """Where resting movers wait for each other in a ring, pass each target one step on.

        Each agent in the ring is one cell closer to the target of the agent waiting for it
        than that agent is, so taking over that target shortens every trip (TSWAP's rule).
        """
        if len(waiting) < 2:
            return
        # Follow "waits for" links by pointer doubling: after more jumps than there are
        # waiting agents every walk has either run out (-1) or is going round a ring, and
        # the places the walks reach are exactly the ring members.
        next_of = np.full(len(self.state) + 1, -1)  # the extra last slot keeps -1 at -1
        next_of[waiting] = waited_for
        jump = next_of.copy()
        for _ in range(len(waiting).bit_length()):
            jump = jump[jump]
        reached = jump[waiting]
        members = np.unique(reached[reached >= 0])
        if len(members) == 0:
            return
        successors = next_of[members]
        self.target[successors] = self.target[members]
        # Their waiting time keeps counting: two movers that steered different ways round an
        # obstacle could trade targets back and forth for ever, and this way they sidestep.
        self.planner.forget(members)

    def _swap_with_settled(self, movers: np.ndarray, settled: np.ndarray) -> None:
        """A settled agent in a mover's way takes the mover's target; the mover takes its cell."""
        if len(movers) == 0:
            return
        _, first = np.unique(settled, return_index=True)
        movers, settled = movers[first], settled[first]
        self.filled[self.target[settled]] = False
        self.state[settled] = MOVING
        self.target[movers], self.target[settled] = self.target[settled], self.target[movers].copy()
        both = np.concatenate([movers, settled])
        self.blocked[both] = 0
        self.planner.forget(both)

    def _counts_as_waiting(self, blocker: np.ndarray) -> np.ndarray:
        """Blocked by something that is not itself on the move (so waiting may never end)."""
        agent = np.maximum(blocker, 0)
        return (blocker < 0) | (self.ahead[agent] == 0)

    def _plan(self, starters: np.ndarray) -> None:
        """Give each routed starter without a field one, in the strictest view that works.

        Nobody enters a seed or another group's shape. One at a time, a mover also goes around
        every agent if it can, else around resting ones, else around settled ones only.
        Concurrent movers swap their way through settled agents; recruits of a changed shape
        first try to go around them, so that agents on kept cells stay put.
        """
        needing = starters[~self.planner.planned(starters)].tolist()
        if not needing:
            return
        occupant = self.occupancy
        agent_here = occupant >= 0
        holder = np.maximum(occupant, 0)
        settled = agent_here & (self.state[holder] == SETTLED)
        resting = agent_here & (self.state[holder] != MOVING)
        owner = self._owner.reshape(occupant.shape[0] + 2, -1)[1:-1, 1:-1]
        for group in np.unique(self.group[needing]).tolist():
            fixed = (occupant == SEED) | ((owner >= 0) & (owner != group))
            if not self.concurrent:
                views = [~fixed & ~agent_here, ~fixed & ~resting, ~fixed & ~settled]
            for agent in [a for a in needing if self.group[a] == group]:
                if self.concurrent:
                    views = [~fixed & ~settled, ~fixed] if self.recruited[agent] else [~fixed]
                cell = self.cell[agent]
                own = [view.copy() for view in views]
                for view in own:
                    view[cell[0], cell[1]] = True
                self.planner.plan(agent, cell, self.world.targets[self.target[agent]], own)

    def _enterable(self, keys: np.ndarray, groups: np.ndarray) -> np.ndarray:
        """Free cells that are not another group's target (a group's shape is its own)."""
        owner = self._owner[keys]
        return (self._occupancy[keys] == FREE) & ((owner < 0) | (owner == groups))

    def _random_free_step(self, agents: np.ndarray, *, own_shape_too: bool) -> np.ndarray:
        """A random direction to an enterable neighbour cell (0 where there is none).

        Idle agents keep out of every shape, their own group's included, unless a new shape
        was drawn over them.
        """
        if len(agents) == 0:
            return np.zeros(0, dtype=np.int64)
        here = self._key(self.cell[agents])
        near = here[:, None] + self._neighbour[None, 1:]
        groups = np.full(len(agents), -1) if own_shape_too else self.group[agents]
        ok = self._enterable(near, groups[:, None])
        # an idle agent that a changed shape now covers must be able to walk out of it
        caught = np.flatnonzero(own_shape_too & (self._owner[here] >= 0))
        ok[caught] = self._occupancy[near[caught]] == FREE
        score = np.where(ok, self.rng.random((len(agents), 4)), -1.0)
        best = np.argmax(score, axis=1)
        return np.where(score.max(axis=1) >= 0, best + 1, 0)

    def _move(self) -> None:
        self.distance += advance(self.offset, self.speed, self.ahead, self.params.limits)
        arrived = np.flatnonzero((self.ahead > 0) & (self.offset >= TOUCH))
        self._occupancy[self._key(self.cell[arrived])] = FREE
        self.cell[arrived] += STEPS[self.direction[arrived]]
        self.ahead[arrived] -= 1
        self.offset[arrived] -= 1.0
        stopped = arrived[self.ahead[arrived] == 0]
        self.offset[stopped] = 0.0
        self.speed[stopped] = 0.0

    def _settle(self) -> np.ndarray:
        """Moving agents resting on their own target settle there."""
        candidates = np.flatnonzero((self.state == MOVING) & (self.ahead == 0))
        goals = self.world.targets[self.target[candidates]]
        done = candidates[(self.cell[candidates] == goals).all(axis=1)]
        self.state[done] = SETTLED
        self.filled[self.target[done]] = True
        self.planner.forget(done)
        return done

    def _overlap_suspects(self) -> np.ndarray:
        """Agents (then seeds, numbered after them) whose square shares a cell with another's.

        A square covers its cell, and the next one too while it is between the two; squares
        that overlap share a cell, so only these few need the exact test. Derived from the
        positions alone, never from the reservations, so it checks them.
        """
        between = np.flatnonzero(self.offset > 0)
        ahead = self.cell[between] + STEPS[self.direction[between]]
        keys = np.concatenate([self._key(self.cell), self._key(ahead), self._seed_keys])
        owners = np.concatenate([np.arange(len(self.cell)), between, self._seed_ids])
        shared = np.bincount(keys, minlength=len(self._occupancy))[keys] > 1
        return np.unique(owners[shared])

    def _observe(self) -> None:
        """Count overlapping pairs (seeds included); note completed groups, free their spares."""
        suspects = self._overlap_suspects()
        if len(suspects):
            everything = np.concatenate([self.positions(), self.world.seeds + 0.5])
            owner = np.concatenate([self.group, self._seed_group])[suspects]
            i, j = overlapping_pairs(everything[suspects])
            self.overlap_total += len(i)
            np.add.at(self.overlaps, owner[i], 1)
            cross = owner[i] != owner[j]
            np.add.at(self.overlaps, owner[j][cross], 1)
        if None in self.completed_at:
            groups = len(self.world.groups)
            filled = np.bincount(self.world.target_group[self.filled], minlength=groups)
            for g in np.flatnonzero(filled == self._targets_per_group).tolist():
                if self.completed_at[g] is None:
                    self.completed_at[g] = self.step_count
                    self.release(self.waiting(g))

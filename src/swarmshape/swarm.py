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

from swarmshape.messages import MessageQueue
from swarmshape.motion import (
    FREE,
    SEED,
    STEPS,
    TOUCH,
    Limits,
    advance,
    inside,
    overlapping_pairs,
    positions,
    resolve_claims,
)
from swarmshape.navigation import FieldPlanner

if TYPE_CHECKING:
    from swarmshape.strategies import Strategy
    from swarmshape.world import World


class State(IntEnum):
    WAITING = 0
    MOVING = 1
    SETTLED = 2
    WANDERING = 3


@dataclass(frozen=True)
class Params:
    """Behaviour knobs shared by all agents."""

    limits: Limits = field(default_factory=Limits)
    wander_rate: float = 0.1
    """Chance per step that a resting wanderer tries a random step."""
    patience: int = 6
    """Steps a blocked mover waits before it replans; after twice as many it sidesteps."""


class Swarm:
    """One run: the world, the agents' arrays, the message queue and the one random generator."""

    def __init__(
        self, world: World, strategy: Strategy, seed: int, params: Params | None = None
    ) -> None:
        self.world = world
        self.strategy = strategy
        self.seed = seed
        self.params = params or Params()
        self.rng = np.random.default_rng(seed)
        n = world.agents
        self.group = np.repeat(np.arange(len(world.groups)), [g.agents for g in world.groups])
        starts = world.start_cells()
        self.cell = starts[self.rng.choice(len(starts), n, replace=False)]
        self.direction = np.zeros(n, dtype=np.int64)
        self.ahead = np.zeros(n, dtype=np.int64)
        self.offset = np.zeros(n)
        self.speed = np.zeros(n)
        self.distance = np.zeros(n)
        self.state = np.full(n, State.WAITING, dtype=np.int8)
        self.target = np.full(n, -1, dtype=np.int64)
        self.blocked = np.zeros(n, dtype=np.int64)
        self.occupancy = np.full(world.size, FREE, dtype=np.int64)
        self.occupancy[world.seeds[:, 0], world.seeds[:, 1]] = SEED
        self.occupancy[self.cell[:, 0], self.cell[:, 1]] = np.arange(n)
        self.filled = np.zeros(len(world.targets), dtype=bool)
        self.target_mask = world.mask(world.targets)
        self.queue = MessageQueue()
        self.planner = FieldPlanner(world.size)
        self.step_count = 0
        self.overlap_total = 0
        self.overlaps = np.zeros(len(world.groups), dtype=np.int64)
        """Overlapping pairs summed over steps, per group (a pair counts for both its groups)."""
        seeds_per_group = [len(g.seeds) for g in world.groups]
        self._seed_group = np.repeat(np.arange(len(world.groups)), seeds_per_group)
        self.completed_at: list[int | None] = [None] * len(world.groups)
        self.strategy.start(self)

    # --- what strategies call -------------------------------------------------------------

    def send(self, sender: int, recipient: int, target: int) -> None:
        """Queue the message "go to `target`" for `recipient`; it arrives next step."""
        self.queue.send(self.step_count, sender, recipient, target)

    def assign(self, agents: np.ndarray, targets: np.ndarray) -> None:
        """Start `agents` moving to `targets` (indices into ``world.targets``)."""
        self.state[agents] = State.MOVING
        self.target[agents] = targets
        self.blocked[agents] = 0
        self.planner.forget(agents)

    def release(self, agents: np.ndarray) -> None:
        """Let `agents` wander: they have nothing left to do."""
        self.state[agents] = State.WANDERING
        self.target[agents] = -1
        self.planner.forget(agents)

    def waiting(self, group: int) -> np.ndarray:
        return np.flatnonzero((self.state == State.WAITING) & (self.group == group))

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

    def _reserve(self) -> None:
        """Every agent that wants a next cell claims it; free cells go to one claimant each."""
        moving = self.state == State.MOVING
        starters = np.flatnonzero(moving & (self.ahead == 0))
        stuck = starters[self.blocked[starters] >= 2 * self.params.patience]
        starters = starters[self.blocked[starters] < 2 * self.params.patience]
        cruisers = np.flatnonzero(moving & (self.ahead == 1))
        cruisers = cruisers[[self.planner.has_plan(a) for a in cruisers.tolist()]]
        self._plan(starters)
        planners = np.concatenate([starters, cruisers])
        origin = self.cell[planners] + STEPS[self.direction[planners]] * self.ahead[planners, None]
        goals = self.world.targets[self.target[planners]]
        wanted = self.planner.directions(planners, origin, goals, self.direction[planners])
        straight = np.ones(len(planners), dtype=bool)
        straight[len(starters) :] = wanted[len(starters) :] == self.direction[cruisers]
        keep = (wanted > 0) & straight

        pushed = self._idle_in_the_way(starters, origin[: len(starters)], wanted[: len(starters)])
        roaming = np.flatnonzero(
            (self.state == State.WANDERING)
            & (self.ahead == 0)
            & (self.rng.random(len(self.state)) < self.params.wander_rate)
        )
        steppers = np.unique(np.concatenate([pushed, roaming]))
        random_dirs = np.concatenate(
            [
                self._random_free_step(steppers, avoid_shape=True),
                self._random_free_step(stuck, avoid_shape=False),
            ]
        )
        agents = np.concatenate([planners[keep], steppers, stuck])
        dirs = np.concatenate([wanted[keep], random_dirs])
        froms = np.concatenate([origin[keep], self.cell[steppers], self.cell[stuck]])
        chosen = dirs > 0
        agents, dirs, froms = agents[chosen], dirs[chosen], froms[chosen]
        cells = froms + STEPS[dirs]
        free = np.zeros(len(cells), dtype=bool)
        ok = inside(cells, self.world.size)
        free[ok] = self.occupancy[cells[ok, 0], cells[ok, 1]] == FREE
        wins = np.zeros(len(cells), dtype=bool)
        wins[free] = resolve_claims(cells[free], self.world.size, self.rng)
        winners, won_cells = agents[wins], cells[wins]
        self.occupancy[won_cells[:, 0], won_cells[:, 1]] = winners
        self.ahead[winners] += 1
        self.direction[winners] = dirs[wins]

        got = np.isin(starters, winners)
        self.blocked[starters[got]] = 0
        self.blocked[starters[~got]] += 1
        if len(stuck):
            self.blocked[stuck] = 0
        replan = starters[self.blocked[starters] == self.params.patience]
        self.planner.forget(np.concatenate([replan, stuck]))

    def _plan(self, starters: np.ndarray) -> None:
        """Give each starter without a field one, in the strictest view that reaches its goal."""
        needing = [a for a in starters.tolist() if not self.planner.has_plan(a)]
        if not needing:
            return
        occupant = self.occupancy
        agent_here = occupant >= 0
        resting = agent_here & (self.state[np.maximum(occupant, 0)] != State.MOVING)
        settled = agent_here & (self.state[np.maximum(occupant, 0)] == State.SETTLED)
        views = [~agent_here, ~resting, ~settled]
        views = [view & (occupant != SEED) for view in views]
        for agent in needing:
            cell = self.cell[agent]
            own = []
            for view in views:
                mine = view.copy()
                mine[cell[0], cell[1]] = True
                own.append(mine)
            self.planner.plan(agent, cell, self.world.targets[self.target[agent]], own)

    def _idle_in_the_way(
        self, starters: np.ndarray, origin: np.ndarray, wanted: np.ndarray
    ) -> np.ndarray:
        """Resting waiting or wandering agents on a cell a starter wants: asked to step aside."""
        ahead_cells = origin[wanted > 0] + STEPS[wanted[wanted > 0]]
        ahead_cells = ahead_cells[inside(ahead_cells, self.world.size)]
        occupant = self.occupancy[ahead_cells[:, 0], ahead_cells[:, 1]]
        occupant = occupant[occupant >= 0]
        idle = (self.state[occupant] == State.WAITING) | (self.state[occupant] == State.WANDERING)
        return occupant[idle & (self.ahead[occupant] == 0)]

    def _random_free_step(self, agents: np.ndarray, *, avoid_shape: bool) -> np.ndarray:
        """A random direction to a free neighbour cell for each agent (0 where there is none)."""
        if len(agents) == 0:
            return np.zeros(0, dtype=np.int64)
        near = self.cell[agents][:, None, :] + STEPS[None, 1:, :]
        flat = near.reshape(-1, 2)
        ok = inside(flat, self.world.size)
        clipped = np.clip(flat, 0, np.array(self.world.size) - 1)
        ok &= self.occupancy[clipped[:, 0], clipped[:, 1]] == FREE
        if avoid_shape:
            ok &= ~self.target_mask[clipped[:, 0], clipped[:, 1]]
        score = np.where(ok.reshape(-1, 4), self.rng.random((len(agents), 4)), -1.0)
        best = np.argmax(score, axis=1)
        return np.where(score.max(axis=1) >= 0, best + 1, 0)

    def _move(self) -> None:
        self.distance += advance(self.offset, self.speed, self.ahead, self.params.limits)
        arrived = np.flatnonzero((self.ahead > 0) & (self.offset >= TOUCH))
        left = self.cell[arrived].copy()
        self.cell[arrived] += STEPS[self.direction[arrived]]
        self.occupancy[left[:, 0], left[:, 1]] = FREE
        self.ahead[arrived] -= 1
        self.offset[arrived] -= 1.0
        stopped = arrived[self.ahead[arrived] == 0]
        self.offset[stopped] = 0.0
        self.speed[stopped] = 0.0

    def _settle(self) -> np.ndarray:
        """Moving agents resting on their own target settle there for good."""
        candidates = np.flatnonzero((self.state == State.MOVING) & (self.ahead == 0))
        goals = self.world.targets[self.target[candidates]]
        done = candidates[(self.cell[candidates] == goals).all(axis=1)]
        self.state[done] = State.SETTLED
        self.filled[self.target[done]] = True
        self.planner.forget(done)
        return done

    def _observe(self) -> None:
        """Count overlapping pairs (seeds included) and note when each group completed."""
        everything = np.concatenate([self.positions(), self.world.seeds + 0.5])
        owner = np.concatenate([self.group, self._seed_group])
        i, j = overlapping_pairs(everything)
        self.overlap_total += len(i)
        np.add.at(self.overlaps, owner[i], 1)
        cross = owner[i] != owner[j]
        np.add.at(self.overlaps, owner[j][cross], 1)
        for g in range(len(self.world.groups)):
            if self.completed_at[g] is None and self.filled[self.world.target_group == g].all():
                self.completed_at[g] = self.step_count

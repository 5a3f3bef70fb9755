"""One swarm driven by a trainer's actions: what the PettingZoo and the batched environments
share (options, spaces, reset, step, reward, rendering), all on stacked numpy arrays."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from swarmshape.config import configure, plugin_options
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Blueprint
from swarmshape.core.shape import Shape
from swarmshape.core.states import LOST, STALLED
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.env.observe import (
    DX,
    DY,
    FRAME_X,
    FRAME_Y,
    GROUP,
    HEADING,
    MOVED_X,
    MOVED_Y,
    NUMBER,
    SLOT,
    STEP,
    Layout,
    encode,
)
from swarmshape.env.relay import NAME, Relay, RelayControl
from swarmshape.env.rewards import CoverageShare, Reward
from swarmshape.errors import InputError
from swarmshape.io.scenario import PALETTE, parse_colour
from swarmshape.runs import load_world, start_cells, start_swarm

FPS = 30
RENDER_MODES = ("human", "rgb_array")
EPISODE_STEPS = 1_000
"""An episode's step limit unless ``max_steps`` is given (the command line's 500,000 is a
whole run's)."""

MOVES = len(STEPS)
"""Stay, or one of four directions (`swarmshape.core.motion.STEPS`, in seed-frame axes)."""

NOT_OPTIONS = {
    "strategy": "the robots are driven by the trainer's actions",
    "seed": "give it to reset(seed=...)",
}
IMAGE_OPTIONS = ("cells", "threshold", "invert", "fit")


class Episode:
    """The swarm, its relay, the observation layout and the reward of one environment."""

    def __init__(
        self,
        shape: str | Path | np.ndarray | None = None,
        *,
        neighbours: int | None = None,
        message_size: int | None = None,
        message_range: tuple[int, int] = (0, 255),
        reward: Reward | None = None,
        **options: Any,
    ) -> None:
        for name, why in NOT_OPTIONS.items():
            if name in options:
                raise InputError(f"{name} is not an environment option: {why}")
        if options.get("max_steps") is None:
            options["max_steps"] = EPISODE_STEPS
        if message_size is not None:  # the trainer's relay's option, given by its name
            options["options"] = {**(options.get("options") or {}), "message_size": message_size}
        if shape is None or isinstance(shape, str | Path):
            self.config = configure(shape, strategy=NAME, **options)
            self.world = load_world(self.config)
        else:
            self.config, self.world = _grid_world(np.asarray(shape), options)
        self.start = start_cells(self.config, self.world)
        senses = self.config.senses()
        cells_in_reach = len(senses.reach())
        neighbours = cells_in_reach if neighbours is None else neighbours
        if not 0 <= neighbours <= 4096:
            raise InputError(f"neighbours must be from 0 to 4096 slots, got {neighbours}")
        self.relay = Relay(plugin_options(self.config))
        message_size = self.relay.message_size
        low, high = message_range
        if not -(2**24) <= low <= high < 2**24:
            raise InputError(
                f"message_range must be two whole numbers low <= high within ±2**24 (exact in "
                f"float32 observations), got {message_range}"
            )
        self.message_range = (int(low), int(high))
        self.layout = Layout(neighbours, message_size, senses.radius)
        self.offset_bound = math.ceil(senses.radius) + 2 + math.ceil(8 * senses.distance_noise)
        """Offsets lie within this (the farthest neighbour may be a cell ahead of its own, as
        may the robot); noisy ones are clipped to it, 8 standard deviations out."""
        self.reward = reward if reward is not None else CoverageShare()
        self.robots = self.world.agents
        self.max_steps = self.config.max_steps
        self.blueprint = Blueprint.of([g.frame_cells for g in self.world.groups])
        """What every robot knows from the start: its group's shape in its seed frame (the
        same for every step, so not repeated in observations)."""
        self.observation_space = self._observation_space()
        self.action_space = self._action_space()
        self.swarm: Swarm | None = None
        self.control: RelayControl | None = None

    # --- spaces ---------------------------------------------------------------------------------

    def _observation_space(self) -> spaces.Box:
        layout, world = self.layout, self.world
        low, high = np.zeros(layout.size, np.float32), np.ones(layout.size, np.float32)
        own_low, own_high = layout.own(low), layout.own(high)
        own_low[MOVED_X : MOVED_Y + 1], own_high[MOVED_X : MOVED_Y + 1] = -2, 2
        own_high[HEADING] = MOVES - 1
        # upper bounds of at least 1: a bound with low == high reads as a mistake to checkers
        own_high[NUMBER] = max(1, max(g.agents for g in world.groups) - 1)
        own_high[GROUP] = max(1, len(world.groups) - 1)
        own_high[STEP] = max(1, self.max_steps)
        frames = [g.pose.to_frame(g.seeds) for g in world.groups]
        frame = max(1, int(np.abs(np.concatenate(frames)).max()))
        for bound, sign in ((low, -1), (high, 1)):
            slots = layout.slots(bound)
            slots[:, DX : DY + 1] = sign * self.offset_bound
            slots[:, FRAME_X : FRAME_Y + 1] = sign * frame
            # a neighbour not heard, or not yet broadcasting, shows zeros
            slots[:, len(SLOT) :] = sign * max(0, sign * self.message_range[sign > 0])
        return spaces.Box(low, high, dtype=np.float32)

    def _action_space(self) -> spaces.Discrete | spaces.MultiDiscrete:
        size = self.layout.message_size
        if size == 0:
            return spaces.Discrete(MOVES)
        low, high = self.message_range
        nvec = np.array([MOVES] + [high - low + 1] * size, dtype=np.int64)
        start = np.array([0] + [low] * size, dtype=np.int64)
        return spaces.MultiDiscrete(nvec, start=start)

    # --- the episode ----------------------------------------------------------------------------

    def reset(self, seed: int) -> np.ndarray:
        """A new swarm from `seed`; every robot's first observation ``(n, size)``."""
        config = dataclasses.replace(self.config, seed=seed)
        self.swarm = start_swarm(config, self.world, self.start, self.relay)
        self.control = self.swarm.driver
        if hasattr(self.reward, "reset"):
            self.reward.reset(self.swarm)
        return self.observe()

    def observe(self) -> np.ndarray:
        noisy = self.config.distance_noise > 0
        return encode(self.control.look(), self.layout, self.offset_bound if noisy else None)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool, bool]:
        """One step with every robot's action (``(n,)`` moves, or ``(n, 1 + message_size)``
        rows of a move and a message): observations, rewards ``(n,)``, whether the shape is
        formed, and whether the episode ran out of steps."""
        if self.swarm is None:
            raise RuntimeError("call reset() before step()")
        self.relay.give(*self.split(actions))
        self.swarm.step()
        rewards = np.asarray(self.reward(self.swarm), dtype=np.float64)
        if rewards.shape != (self.robots,):
            raise ValueError(f"the reward gave shape {rewards.shape}, not ({self.robots},)")
        swarm = self.swarm
        formed = swarm.complete and not swarm.faults.ahead(swarm.step_count)
        out_of_steps = not formed and self.swarm.step_count >= self.max_steps
        return self.observe(), rewards, formed, out_of_steps

    def acting(self) -> np.ndarray:
        """Robots that still act: not removed or stalled by a fault (``faults`` and
        ``failure_rate`` options); the others' actions are ignored."""
        state = self.swarm.state
        return (state != LOST) & (state != STALLED)

    def split(self, actions: Any) -> tuple[np.ndarray, np.ndarray]:
        """Moves ``(n,)`` and messages ``(n, message_size)`` from stacked actions, checked."""
        actions = np.asarray(actions)
        n, size = self.robots, self.layout.message_size
        shape = (n,) if size == 0 else (n, 1 + size)
        if actions.shape != shape or not np.issubdtype(actions.dtype, np.integer):
            raise ValueError(f"actions must be integers of shape {shape}, got {actions.shape} "
                             f"{actions.dtype}")  # fmt: skip
        if size == 0:
            moves, messages = actions, np.zeros((n, 0), dtype=np.int64)
        else:
            moves, messages = actions[:, 0], actions[:, 1:]
            low, high = self.message_range
            if messages.size and (messages.min() < low or messages.max() > high):
                raise ValueError(f"a message value lies outside message_range {low}..{high}")
        if moves.size and (moves.min() < 0 or moves.max() >= MOVES):
            raise ValueError(f"a move is not 0 (stay) to {MOVES - 1} (a direction)")
        return moves.astype(np.int64), messages.astype(np.int64)

    def coverage(self) -> float:
        """Filled target cells over target cells, now."""
        return float(self.swarm.filled.mean()) if self.swarm is not None else 0.0


def _grid_world(grid: np.ndarray, options: dict[str, Any]) -> tuple[Any, World]:
    """A run on a boolean grid given in code (True: a cell of the shape)."""
    if grid.ndim != 2 or grid.dtype != bool:
        raise InputError(
            f"shape must be a path or a 2-D boolean grid, got {grid.dtype} {grid.shape}"
        )
    given = sorted(name for name in IMAGE_OPTIONS if options.get(name) is not None)
    if given:
        raise InputError(f"{given[0]} applies to an image file, not to a grid given in code")
    config = configure(None, strategy=NAME, **options)
    spec = GroupSpec("grid", Shape(grid), parse_colour(PALETTE[0]), config.agents)
    return config, build_world([spec], config.arena, "grid", config.start == "packed")


class Host:
    """What both environments are built on: an `Episode`, a `Screen`, `render`, `coverage`."""

    def __init__(
        self,
        shape: str | Path | np.ndarray | None = None,
        render_mode: str | None = None,
        render_size: tuple[int, int] = (640, 400),
        **options: Any,
    ) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(
                f"render_mode must be one of {RENDER_MODES} or None, got {render_mode!r}"
            )
        self.episode = Episode(shape, **options)
        self.render_mode = render_mode
        self.screen = None
        if render_mode is not None:
            from swarmshape.ui.screen import Screen  # pygame, only to render

            self.screen = Screen(render_mode, render_size, FPS)

    @property
    def layout(self) -> Layout:
        """Where each value sits in an observation."""
        return self.episode.layout

    @property
    def blueprint(self) -> Blueprint:
        """Every group's shape in its seed frame, as each robot knows it."""
        return self.episode.blueprint

    def render(self) -> np.ndarray | None:
        return None if self.screen is None else self.screen.render(self.episode.swarm)

    def show(self) -> None:
        """After a reset or a step: a window follows the swarm."""
        if self.screen is not None:
            self.screen.update(self.episode.swarm)

    def close(self) -> None:
        if self.screen is not None:
            self.screen.close()

    def coverage(self) -> float:
        """Filled target cells over target cells, now."""
        return self.episode.coverage()

"""The PettingZoo `ParallelEnv`: every robot is an agent (``robot_0`` ...), observations,
actions, rewards and flags are dicts keyed by agent. Create it as PettingZoo's environments are
created: ``swarmshape.env.parallel_env(shape=..., **options)``; see `swarmshape.env`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv

from swarmshape.env.episode import FPS, RENDER_MODES, Host


class SwarmEnv(Host, ParallelEnv):
    """A swarm forming a shape, one agent per robot (see `swarmshape.env` for the options)."""

    metadata = {  # noqa: RUF012  (PettingZoo's convention: a class attribute)
        "name": "swarmshape_v0",
        "render_modes": list(RENDER_MODES),
        "render_fps": FPS,
        "is_parallelizable": True,
    }

    def __init__(self, shape: str | Path | np.ndarray | None = None, **options: Any) -> None:
        Host.__init__(self, shape, **options)
        self.possible_agents = [f"robot_{i}" for i in range(self.episode.robots)]
        self.index = {agent: i for i, agent in enumerate(self.possible_agents)}
        width, height = self.episode.world.size
        self.state_space = spaces.Box(0, max(width, height) - 1, (self.episode.robots, 2), np.int64)
        self.agents: list[str] = []
        self._np_random: np.random.Generator | None = None
        self._np_random_seed: int | None = None

    @property
    def np_random(self) -> np.random.Generator:
        """Draws each episode's seed; seeded by ``reset(seed=...)``, else from entropy."""
        if self._np_random is None:
            self._np_random, self._np_random_seed = seeding.np_random()
        return self._np_random

    def observation_space(self, agent: str) -> Any:
        return self.episode.observation_space

    def action_space(self, agent: str) -> Any:
        return self.episode.action_space

    def reset(
        self, seed: int | None = None, options: dict | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
        if seed is not None:
            self._np_random, self._np_random_seed = seeding.np_random(seed)
        obs = self.episode.reset(int(self.np_random.integers(2**63)))
        self.agents = self.possible_agents[:]
        self.show()
        return dict(zip(self.agents, obs, strict=True)), {agent: {} for agent in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Robots with no action stay where they are and repeat their last message. A robot a
        fault removes or stalls terminates then (it never acts again)."""
        if not self.agents:
            return {}, {}, {}, {}, {}
        episode = self.episode
        unknown = sorted(set(actions) - set(self.index))
        if unknown:
            raise ValueError(f"no agent {unknown[0]!r} in this environment")
        stacked = episode.stacked({self.index[agent]: act for agent, act in actions.items()})
        obs, rewards, formed, out_of_steps = episode.step(stacked)
        live, acting = self.agents, episode.acting()
        index = [self.index[agent] for agent in live]
        observations = dict(zip(live, obs[index], strict=True))
        reward = dict(zip(live, rewards[index].tolist(), strict=True))
        terminations = {
            agent: formed or not acting[i] for agent, i in zip(live, index, strict=True)
        }
        truncations = dict.fromkeys(live, out_of_steps)
        infos: dict[str, dict] = {agent: {} for agent in live}
        ended = formed or out_of_steps
        self.agents = [] if ended else [agent for agent in live if not terminations[agent]]
        self.show()
        return observations, reward, terminations, truncations, infos

    def state(self) -> np.ndarray:
        """A global view for centralised critics: every robot's cell ``(n, 2)`` in world axes
        (in `state_space`)."""
        return self.episode.swarm.cell.copy()


def parallel_env(shape: str | Path | np.ndarray | None = None, **options: Any) -> SwarmEnv:
    """A `SwarmEnv` (PettingZoo's ``parallel_env`` creator)."""
    return SwarmEnv(shape, **options)

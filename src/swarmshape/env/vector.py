"""The batched interface: one shared policy over every robot. A Gymnasium `VectorEnv` whose
sub-environments are the robots of one swarm (``num_envs`` = robots): observations
``(n, size)``, actions ``(n,)`` or ``(n, 1 + message_size)``, rewards and flags ``(n,)``, as
stacked numpy arrays with no dict per robot."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from swarmshape.env.episode import FPS, RENDER_MODES, Host


class SwarmVectorEnv(Host, VectorEnv):
    """A swarm forming a shape, batched over its robots (see `swarmshape.env` for the options).

    All robots share one episode: they terminate together when the shape is formed and are
    truncated together at ``max_steps``. The step after that resets the whole swarm (Gymnasium's
    ``NEXT_STEP`` autoreset: the action is ignored, rewards are 0, flags False); a reset asked
    for by ``reset_mask`` must cover every robot. A robot a fault removed or stalled stays in
    the batch (it senses nothing, or is never heard, and its actions are ignored);
    ``infos["acting"]`` says which robots still act. `render` returns one frame of the swarm.
    """

    metadata = {  # noqa: RUF012  (Gymnasium's convention: a class attribute)
        "render_modes": list(RENDER_MODES),
        "render_fps": FPS,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(self, shape: str | Path | np.ndarray | None = None, **options: Any) -> None:
        Host.__init__(self, shape, **options)
        self.num_envs = self.episode.robots
        self.single_observation_space = self.episode.observation_space
        self.single_action_space = self.episode.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._ended = False

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        mask = (options or {}).get("reset_mask")
        if mask is not None and not np.all(mask):
            raise ValueError("the robots share one episode: reset_mask must cover every robot")
        obs = self.episode.reset(int(self.np_random.integers(2**63)))
        self._ended = False
        self.show()
        return obs, {}

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        n = self.num_envs
        if self._ended:
            obs, infos = self.reset()
            return obs, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), infos
        obs, rewards, formed, out_of_steps = self.episode.step(actions)
        self._ended = formed or out_of_steps
        self.show()
        infos = {"acting": self.episode.acting(), "_acting": np.ones(n, dtype=bool)}
        return obs, rewards, np.full(n, formed), np.full(n, out_of_steps), infos

    def close_extras(self, **kwargs: Any) -> None:
        Host.close(self)


def vector_env(shape: str | Path | np.ndarray | None = None, **options: Any) -> SwarmVectorEnv:
    """A `SwarmVectorEnv`: the batched interface."""
    return SwarmVectorEnv(shape, **options)

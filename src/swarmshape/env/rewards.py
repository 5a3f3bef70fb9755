"""Rewards: any callable ``reward(swarm) -> (n,) floats``, one per robot, called after every
step; if it has a ``reset(swarm)`` method, that is called at the start of each episode.

A reward is the trainer's business and may read the whole `Swarm`; the robots' observations
never do. The default, `CoverageShare`, splits the change in coverage among the robots that
made it, so the rewards of all robots over an episode add up to its final coverage minus its
first.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from swarmshape.core.swarm import Swarm


class Reward(Protocol):
    def __call__(self, swarm: Swarm) -> np.ndarray:
        """Each robot's reward for the step just taken ``(n,)``."""


class CoverageShare:
    """A robot's share of the change in coverage: ``+1 / targets`` in the step it comes to rest
    on a target cell of its group (the moment that cell counts as filled), ``-1 / targets`` in
    the step it sets off from one, else 0."""

    def reset(self, swarm: Swarm) -> None:
        self.world = None
        self.before = self.resting(swarm)

    def resting(self, swarm: Swarm) -> np.ndarray:
        """Robots at rest on a target cell of their group ``(n,)``: each fills that cell."""
        world = swarm.world
        if world is not self.world:  # a new episode, or a fault re-formed the shape smaller
            self.world = world
            self.index = np.full(world.size, -1, dtype=np.int64)
            self.index[world.targets[:, 0], world.targets[:, 1]] = np.arange(len(world.targets))
            self.share = 1.0 / max(1, len(world.targets))
        at = self.index[swarm.cell[:, 0], swarm.cell[:, 1]]
        mine = swarm.world.target_group[np.maximum(at, 0)] == swarm.group
        return (swarm.ahead == 0) & (at >= 0) & mine

    def __call__(self, swarm: Swarm) -> np.ndarray:
        now = self.resting(swarm)
        reward = (now.astype(np.float64) - self.before) * self.share
        self.before = now
        return reward

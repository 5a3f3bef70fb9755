"""The trainer's side of the local-program contract: a `Program` whose moves and messages are
the actions a trainer gave, and a driver that shows the trainer the very `Perception` the
robots then act on.

A local program is asked to act in the middle of a swarm step, right after the robots sense;
a trainer wants the senses first and answers later. Nothing changes the swarm between the end
of one step and the start of the next, so `RelayControl.look` senses at the end of a step (the
same draws from the run's generator, in the same order) and the next step acts on that
perception instead of sensing again.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from swarmshape.core.local import LocalControl, Memory, Program
from swarmshape.core.options import option
from swarmshape.core.perception import Perception

if TYPE_CHECKING:
    from swarmshape.core.swarm import Swarm

NAME = "swarmshape.env.relay:Relay"
"""How a run driven by a trainer names its strategy (it is code, never loaded from a file)."""


class Relay(Program):
    """Moves and broadcasts given from outside, one step at a time (see `give`)."""

    name = "trainer"
    description = "local: the actions a trainer gives through swarmshape.env"

    @dataclass(frozen=True)
    class Options:
        message_size: int = option(
            0, "whole numbers each robot broadcasts, chosen by the trainer", at_least=0, at_most=64
        )

    def __init__(self, options: Options | None = None) -> None:
        super().__init__(options)
        self.message_size = self.options.message_size
        self.moves = np.zeros(0, dtype=np.int64)
        self.messages = np.zeros((0, self.message_size), dtype=np.int64)

    def give(self, moves: np.ndarray, messages: np.ndarray) -> None:
        """The moves ``(n,)`` and broadcasts ``(n, message_size)`` of the next step."""
        self.moves, self.messages = moves, messages

    def act(
        self, sense: Perception, memory: Memory, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        return self.moves, self.messages

    def finished(self, memory: Memory) -> np.ndarray:
        """Every robot at rest counts as settled: the trainer, not a program, decides when a
        robot is done, so a cell is filled while a robot of its group rests on it."""
        return np.ones(len(memory), dtype=bool)

    def drive(self, swarm: Swarm) -> RelayControl:
        return RelayControl(swarm, self)


class RelayControl(LocalControl):
    """`LocalControl` that senses when the trainer asks (`look`) and acts on that perception."""

    sensed: Perception

    def look(self) -> Perception:
        """What every robot senses now: the perception the next step's actions answer."""
        self.sensed = LocalControl.perceive(self)
        return self.sensed

    def perceive(self) -> Perception:
        return self.sensed

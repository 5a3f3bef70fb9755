"""The one message type of the paper, "go to target T", and the queue that carries it.

Messages sent during a step are delivered at the start of the next one, like a radio hop.
The log keeps every message ever sent so that tests and users can read the conversation.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

SEEDS = -1
"""Sender id of the seed robots, which send each group's first message."""


@dataclass(frozen=True)
class Message:
    """At `step`, `sender` (an agent id, or SEEDS) told `recipient` to go to target `target`."""

    step: int
    sender: int
    recipient: int
    target: int


class MessageQueue:
    """First in, first out; nothing is lost or reordered."""

    def __init__(self) -> None:
        self._pending: deque[Message] = deque()
        self.log: list[Message] = []

    def send(self, step: int, sender: int, recipient: int, target: int) -> Message:
        message = Message(step, sender, recipient, target)
        self._pending.append(message)
        self.log.append(message)
        return message

    def deliver(self) -> list[Message]:
        """Hand over everything sent so far."""
        delivered = list(self._pending)
        self._pending.clear()
        return delivered

"""The one message type of the paper, "go to target T", and the queue that carries it.

Messages sent during a step are delivered at the start of the next one, like a radio hop.
The log keeps every message ever sent so that tests and users can read the conversation.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, replace

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

    @property
    def pending(self) -> list[Message]:
        """Sent and not yet delivered."""
        return list(self._pending)

    def retarget(self, new_index: Sequence[int]) -> None:
        """Renumber pending messages' targets after the shape changed; drop those whose
        target is gone (``new_index[target] < 0``). The log keeps what was said."""
        kept = [replace(m, target=int(new_index[m.target])) for m in self._pending]
        self._pending = deque(m for m in kept if m.target >= 0)

    def deliver(self) -> list[Message]:
        """Hand over everything sent so far."""
        delivered = list(self._pending)
        self._pending.clear()
        return delivered

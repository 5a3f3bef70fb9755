"""The one message type of the paper, "go to target T", and the queue that carries it.

Messages sent during a step are delivered at the start of the next one, like a radio hop.
The log keeps every message ever sent so that tests and users can read the conversation.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import astuple, dataclass, replace
from typing import Any

import numpy as np

from swarmshape.core.snapshot import Snapshot

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

    def retarget(self, new_index: Sequence[int] | np.ndarray) -> None:
        """Renumber pending messages' targets after the shape changed; drop those whose
        target is gone (``new_index[target] < 0``). The log keeps what was said."""
        kept = [replace(m, target=int(new_index[m.target])) for m in self._pending]
        self._pending = deque(m for m in kept if m.target >= 0)

    def drop(self, recipients: np.ndarray) -> None:
        """Forget pending messages to `recipients` (robots a fault took); the log keeps them."""
        gone = set(np.asarray(recipients).tolist())
        self._pending = deque(m for m in self._pending if m.recipient not in gone)

    def deliver(self) -> list[Message]:
        """Hand over everything sent so far."""
        delivered = list(self._pending)
        self._pending.clear()
        return delivered

    def snapshot(self) -> dict[str, Any]:
        """The log and the pending messages, one row ``(step, sender, recipient, target)`` each."""
        return {"log": _table(self.log), "pending": _table(self._pending)}

    @classmethod
    def restored(cls, saved: Snapshot, robots: int, targets: int) -> MessageQueue:
        queue = cls()
        queue.log = [Message(*row) for row in saved.array("log", np.int64, (None, 4)).tolist()]
        pending = saved.array("pending", np.int64, (None, 4))
        recipient, target = pending[:, 2], pending[:, 3]
        if ((recipient < 0) | (recipient >= robots) | (target < 0) | (target >= targets)).any():
            raise saved.error("pending", "names a robot or a target that does not exist")
        queue._pending = deque(Message(*row) for row in pending.tolist())
        return queue


def _table(messages: Iterable[Message]) -> np.ndarray:
    return np.array([astuple(m) for m in messages], dtype=np.int64).reshape(-1, 4)

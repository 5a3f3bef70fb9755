"""Strategy plug-ins: who goes to which target, and when.

A strategy is any class with a ``name``, a one-line ``description`` and the two hooks of
`Strategy`; `register` makes it reachable as ``--strategy NAME``. The core calls ``start`` once
after placing the agents and ``on_settled`` whenever agents reach their targets.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from swarmshape.errors import InputError

if TYPE_CHECKING:
    from swarmshape.swarm import Swarm


class Strategy(Protocol):
    name: ClassVar[str]
    description: ClassVar[str]

    def start(self, swarm: Swarm) -> None:
        """Hand out the first targets (by message or by ``swarm.assign``)."""

    def on_settled(self, swarm: Swarm, agents: np.ndarray) -> None:
        """React to `agents` having settled on their targets this step."""


REGISTRY: dict[str, type[Strategy]] = {}


def register(cls: type[Strategy]) -> type[Strategy]:
    """Class decorator: make `cls` available by its ``name``."""
    REGISTRY[cls.name] = cls
    return cls


def get(name: str) -> type[Strategy]:
    """The registered strategy class called `name`."""
    try:
        return REGISTRY[name]
    except KeyError:
        known = ", ".join(sorted(REGISTRY))
        raise InputError(f"unknown strategy {name!r}; choose one of {known}") from None


from swarmshape.strategies import paper  # noqa: E402,F401  (registers the built-ins)

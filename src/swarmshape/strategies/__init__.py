"""Strategy plug-ins: who goes to which target, and when; the core moves agents there.

A strategy is a class with a ``name``, a one-line ``description``, ``concurrent`` (True when
many agents move at once, False for the paper's one at a time) and the two hooks of `Strategy`.
`register` makes it reachable as ``--strategy NAME``; any importable class also works as
``--strategy package.module:Class``, and installed packages can offer theirs under the
entry-point group ``swarmshape.strategies``. A complete user strategy::

    import numpy as np
    from swarmshape.strategies import register

    @register
    class NearestFirst:
        name = "nearest-first"
        description = "targets in order, each takes the nearest free agent of its group"
        concurrent = True

        def start(self, swarm):
            free = np.ones(len(swarm.cell), dtype=bool)
            for target, cell in enumerate(swarm.world.targets):
                mine = free & (swarm.group == swarm.world.target_group[target])
                distance = np.abs(swarm.cell - cell).sum(axis=1)
                agent = np.flatnonzero(mine)[np.argmin(distance[mine])]
                free[agent] = False
                swarm.assign(np.array([agent]), np.array([target]))

        def on_settled(self, swarm, agents):
            pass
"""

from __future__ import annotations

import importlib
import inspect
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from swarmshape.errors import InputError

if TYPE_CHECKING:
    from swarmshape.swarm import Swarm

ENTRY_POINTS = "swarmshape.strategies"


class Strategy(Protocol):
    name: ClassVar[str]
    description: ClassVar[str]
    concurrent: ClassVar[bool]

    def start(self, swarm: Swarm) -> None:
        """Hand out the first targets (by ``swarm.send`` or ``swarm.assign``)."""

    def on_settled(self, swarm: Swarm, agents: np.ndarray) -> None:
        """React to `agents` having settled on their targets this step."""


REGISTRY: dict[str, type[Strategy]] = {}


def register(cls: type[Strategy]) -> type[Strategy]:
    """Class decorator: make `cls` available by its ``name``."""
    REGISTRY[cls.name] = cls
    return cls


def available() -> dict[str, type[Strategy]]:
    """Registered strategies plus those installed packages offer, by name."""
    found = dict(REGISTRY)
    for entry in entry_points(group=ENTRY_POINTS):
        found.setdefault(entry.name, entry.load())
    return found


def get(name: str) -> type[Strategy]:
    """The strategy class called `name`, or named ``package.module:Class``."""
    if ":" in name:
        cls = _import(name)
    else:
        known = available()
        if name not in known:
            choices = ", ".join(sorted(known))
            raise InputError(f"unknown strategy {name!r}; choose one of {choices}")
        cls = known[name]
    missing = [hook for hook in ("start", "on_settled") if not callable(getattr(cls, hook, None))]
    if missing:
        raise InputError(f"strategy {name!r} lacks {' and '.join(missing)}(swarm, ...)")
    return cls


def create(name: str, **options: Any) -> Strategy:
    """A new strategy, given those of `options` its constructor accepts (e.g. ``order``)."""
    cls = get(name)
    accepted = inspect.signature(cls).parameters
    return cls(**{key: value for key, value in options.items() if key in accepted})


def _import(spec: str) -> type[Strategy]:
    module_name, _, attribute = spec.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise InputError(f"strategy {spec!r}: cannot import {module_name} ({error})") from None
    try:
        return getattr(module, attribute)
    except AttributeError:
        raise InputError(f"strategy {spec!r}: {module_name} has no {attribute}") from None


from swarmshape.strategies import concurrent, paper  # noqa: E402,F401  (registers built-ins)

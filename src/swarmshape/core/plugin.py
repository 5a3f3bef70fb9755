"""The one base of both plug-in kinds: a name, a line of help, what it can form, its options.

A central planner (`swarmshape.core.steering.Strategy`) and a local robot program
(`swarmshape.core.local.Program`) both subclass `Plugin`. Each brings the driver the swarm runs
it with (`drive`), and may declare its own ``Options``: a frozen dataclass whose fields are
`swarmshape.core.options.option` declarations (or plain fields with a default)::

    @dataclass(frozen=True)
    class Options:
        reach: int = option(8, "hops a robot relays news", at_least=1)

The run fills them in from ``--set reach=12``, a scenario's ``[options]`` table, a sweep's
``options.reach = [4, 8]`` or ``configure(..., options={"reach": 12})``, each value checked
against its declaration, and the plug-in reads ``self.options.reach``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    from swarmshape.core.swarm import Driver, Swarm


@dataclass(frozen=True)
class NoOptions:
    """The options of a plug-in that declares none."""


class Plugin:
    """Base class of plug-ins; subclass `Strategy` or `Program`, not this."""

    name: ClassVar[str]
    description: ClassVar[str]
    kind: ClassVar[str]
    """``"central"`` or ``"local"``: which run settings it reads, how it is listed."""
    grows_from_seeds: ClassVar[bool] = False
    """True if the plug-in builds outward from the seeds, so it can form only a shape's
    `Shape.solid` part (one piece with its seeds, no holes): checks and tests then give it
    solid shapes, and a run warns about any other."""
    enters_from_outside: ClassVar[bool] = False
    """True if its robots, once on the shape, step off it only toward an empty cell they
    sense: a piece of the shape that touches only pockets of other pieces, beyond the sensing
    radius of them (`Shape.sealed`), then fills only from robots that start in those pockets,
    and a run warns about such a shape."""
    Options: ClassVar[type[Any]] = NoOptions
    """Its own settings (see the module's docstring)."""

    def __init__(self, options: Any = None) -> None:
        self.options = self.Options() if options is None else options

    def drive(self, swarm: Swarm) -> Driver:
        """The swarm's driver for this plug-in (the core's side of the contract)."""
        raise NotImplementedError

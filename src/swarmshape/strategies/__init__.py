"""The strategy registry: every plug-in by name, built-in, installed, or named on the command line.

A plug-in is of one of two kinds: a central planner subclasses `swarmshape.core.steering.Strategy`,
a local robot program subclasses `swarmshape.core.local.Program`. `register` makes it reachable as
``--strategy NAME``; installed packages offer theirs under the entry-point group
``swarmshape.strategies``. Code can also be named directly, ``path/to/file.py:Class`` or
``package.module:Class``, but only by the user on the command line or from Python: scenario and
state files are data and name strategies only by registered or installed names. The README's
"Writing a strategy" shows a complete one, and ``examples/my_strategy.py`` runs it.
"""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import inspect
import sys
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType
from typing import Any

from swarmshape.core.guard import PluginCode
from swarmshape.core.local import Program
from swarmshape.core.options import specs
from swarmshape.core.plugin import Plugin
from swarmshape.core.steering import Strategy
from swarmshape.errors import InputError

ENTRY_POINTS = "swarmshape.strategies"

REGISTRY: dict[str, type[Plugin]] = {}
LOADED: dict[Path, ModuleType] = {}
"""Files of code run so far (strategies, benchmark policies), by their resolved paths."""


def register(cls: type[Plugin]) -> type[Plugin]:
    """Class decorator: make `cls` available by its ``name``."""
    REGISTRY[cls.name] = cls
    return cls


def available() -> dict[str, type[Plugin]]:
    """Registered strategies plus those installed packages offer, by name."""
    found = dict(REGISTRY)
    for entry in entry_points(group=ENTRY_POINTS):
        found.setdefault(entry.name, entry.load())
    return found


def is_code(name: str) -> bool:
    """Whether `name` points at code (``file.py:Class`` or ``module:Class``) rather than naming
    a registered or installed strategy."""
    return ":" in name


def get(name: str) -> type[Plugin]:
    """The plug-in class called `name`, or found at ``file.py:Class`` or ``module:Class``."""
    if is_code(name):
        cls = _import(name)
    else:
        # a built-in's name needs no scan of the installed packages (6 ms, at every swarm made)
        known = REGISTRY if name in REGISTRY else available()
        if name not in known:
            choices = ", ".join(sorted(known))
            raise InputError(f"unknown strategy {name!r}; choose one of {choices}")
        cls = known[name]
    if not (isinstance(cls, type) and issubclass(cls, Strategy | Program)):
        raise InputError(
            f"strategy {name!r} is not a subclass of swarmshape.Strategy or swarmshape.Program"
        )
    if not isinstance(getattr(cls, "name", None), str):
        raise InputError(f"strategy {name!r} has no name; a plug-in class sets name = '...'")
    if not dataclasses.is_dataclass(cls.Options):
        raise InputError(f"strategy {name!r}: its Options must be a @dataclass(frozen=True)")
    if is_code(name) and available().get(cls.name, cls) is not cls:  # summaries, metrics, rows
        raise InputError(
            f"strategy {name!r} calls itself {cls.name!r}, a built-in strategy's name, which "
            "its results would then claim; give it a name of its own"
        )
    return cls


def create(strategy: str | type[Plugin], options: Any = None) -> Plugin:
    """A new plug-in (by name or class) with its `options` (an instance of its ``Options``;
    None: the defaults)."""
    cls = strategy if isinstance(strategy, type) else get(strategy)
    try:  # the contract of a plug-in's constructor, checked before its code runs
        inspect.signature(cls).bind(options)
    except TypeError:
        raise InputError(
            f"strategy {cls.name!r} cannot be made: its __init__ must take its options, "
            "as in def __init__(self, options=None), and pass them to super().__init__"
        ) from None
    return cls(options)


def owners_of(option_name: str) -> list[str]:
    """The registered and installed plug-ins that declare an option called `option_name`."""
    return sorted(
        name
        for name, cls in available().items()
        if any(spec.name == option_name for spec in specs(cls.Options))
    )


def _import(spec: str) -> type[Plugin]:
    with PluginCode.named(spec).running(" as it was loaded"):  # wherever it is first looked up
        return load(spec)


def load(spec: str, what: str = "strategy") -> Any:
    """What ``path/to/file.py:Name`` or ``package.module:Name`` names (a strategy, or any
    other code a user names the same way: `what` it is, for the messages)."""
    module_name, _, attribute = spec.rpartition(":")
    if module_name.endswith(".py"):
        module = _load_file(Path(module_name), spec, what)
    else:
        try:
            module = importlib.import_module(module_name)
        except (ImportError, ValueError, TypeError) as error:  # also "" and ".relative"
            raise InputError(f"{what} {spec!r}: cannot import {module_name} ({error})") from None
    try:
        return getattr(module, attribute)
    except AttributeError:
        raise InputError(f"{what} {spec!r}: {module_name} has no {attribute}") from None


def _load_file(path: Path, spec: str, what: str) -> ModuleType:
    """Run a file the user named, as a module of its own."""
    try:
        is_file = path.is_file()
    except OSError as error:  # a name too long to look up, say
        raise InputError(f"{what} {spec!r}: cannot read {path} ({error.strerror})") from None
    if not is_file:
        raise InputError(f"{what} {spec!r}: no such file {path}")
    key = path.resolve()
    if key not in LOADED:  # once per process: a file may keep state at module level
        name = f"swarmshape_strategy_{path.stem}"
        found = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(found)
        sys.modules[name] = module  # so that its classes can be found again, e.g. by name
        found.loader.exec_module(module)
        LOADED[key] = module
    return LOADED[key]


from swarmshape.strategies import (  # noqa: E402,F401  (built-ins)
    concurrent,
    local_swap,
    mean_shift,
    paper,
    self_assembly,
)

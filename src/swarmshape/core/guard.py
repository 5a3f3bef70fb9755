"""An error in a plug-in's code is the plug-in's: one line that names it and the line of its
code that failed, not "internal error, please report it".

A failure is the plug-in's when its traceback passes through the plug-in's own code (the
modules or files of its class and of the bases it brings along, as opposed to swarmshape's):
an exception it raised, a write to a read-only view, a robot it named that does not exist
(refused by the core, called from its code), or ``sys.exit``. A failure wholly inside
swarmshape stays a bug of ours. A stop from outside (Ctrl+C, a signal, a time limit) passes
through untouched, wherever it struck.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from dataclasses import dataclass
from types import TracebackType

from swarmshape.errors import PluginError, Stopped, Terminated

LONGEST = 200
"""Characters of the plug-in's own error message that the line keeps."""


def _ours(module: str) -> bool:
    return module in ("swarmshape", "builtins") or module.startswith("swarmshape.")


@dataclass(frozen=True)
class PluginCode:
    """Where a plug-in's code lives, and what the messages call it."""

    name: str
    modules: frozenset[str] = frozenset()
    files: frozenset[str] = frozenset()

    @classmethod
    def of(cls, plugin: object) -> PluginCode:
        """The code of a plug-in object (or class): its class's modules and those of its bases
        that are not swarmshape's."""
        kind = plugin if isinstance(plugin, type) else type(plugin)
        modules = {base.__module__ for base in kind.__mro__} - {"builtins"}
        return cls(str(getattr(kind, "name", kind.__name__)),
                   frozenset(m for m in modules if not _ours(m)))  # fmt: skip

    @classmethod
    def named(cls, spec: str) -> PluginCode:
        """The code a ``file.py:Class`` or ``module:Class`` names, before it is even loaded
        (its import and its constructor run user code too)."""
        where = spec.rpartition(":")[0]
        if where.endswith(".py"):
            return cls(spec, files=frozenset({os.path.realpath(where)}))
        return cls(spec, modules=frozenset() if _ours(where) else frozenset({where}))

    def where(self, trace: TracebackType | None) -> tuple[str, int] | None:
        """The file and line of the innermost frame of this code in `trace`, if any."""
        found = None
        while trace is not None:
            frame = trace.tb_frame
            module = frame.f_globals.get("__name__", "")
            path = frame.f_code.co_filename
            if module in self.modules or os.path.realpath(path) in self.files:
                found = (os.path.basename(path), trace.tb_lineno)
            trace = trace.tb_next
        return found

    @contextlib.contextmanager
    def running(self, when: str = "") -> Iterator[None]:
        """Turn a failure of this code, while the block runs, into a `PluginError`; `when`
        says when it happened (" at step 12")."""
        try:
            yield
        except (KeyboardInterrupt, Terminated, Stopped, PluginError):  # the last: said already
            raise
        except BaseException as error:
            where = self.where(error.__traceback__)
            if where is None:
                raise
            raise PluginError(self.describe(error, when, where)) from error

    def describe(self, error: BaseException, when: str, where: tuple[str, int]) -> str:
        place = f"({where[0]}, line {where[1]})"
        if isinstance(error, SystemExit):
            return (
                f"strategy {self.name!r} called sys.exit({error.code!r}){when} {place}; a "
                "strategy returns from its hooks, it never ends the program"
            )
        said = str(error)
        said = said if len(said) <= LONGEST else said[: LONGEST - 3] + "..."
        what = f"{type(error).__name__}: {said}" if said else type(error).__name__
        return f"strategy {self.name!r} failed{when}: {what} {place}"

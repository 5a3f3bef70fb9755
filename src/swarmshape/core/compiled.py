"""`njit`: numba's compiler (with its on-disk cache), put off until a kernel's first call.

Importing numba takes about 0.2 s, a third of the command line's start-up; a command that never
steps (``--help``, a bad input, a plot) should not pay it. A kernel's first call imports numba,
compiles the kernel (or loads it from numba's cache) and the kernels it calls, and puts the
compiled function in its module in place of the stand-in, so calls from there on go straight to
numba's code.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from typing import Any, TypeVar, cast

F = TypeVar("F", bound=Callable[..., Any])


_compiling = 0
"""Kernels being compiled now (a kernel compiles the kernels it calls first)."""
_compile_seconds = 0.0
"""Seconds spent in kernels' first calls, which compile them, so far."""


def compiling() -> bool:
    """Whether a kernel is being compiled, or loaded from numba's cache, now: a time limit on
    a step (`swarmshape check`) counts the strategy's work, not this, which takes seconds
    on a cold cache."""
    return _compiling > 0


def compile_seconds() -> float:
    """Seconds spent compiling kernels (in their first calls) so far, in this process."""
    return _compile_seconds


class _Kernel:
    """A kernel not compiled yet: calling it compiles it, then calls the compiled function."""

    def __init__(self, python: Callable[..., Any]) -> None:
        functools.update_wrapper(self, python)
        self.python = python
        self.compiled: Callable[..., Any] | None = None

    def __call__(self, *args: Any) -> Any:
        if self.compiled is not None:
            return self.compiled(*args)
        global _compiling, _compile_seconds
        _compiling += 1
        began = time.perf_counter()
        try:  # numba compiles at the first call, for its arguments' types
            return self.compile()(*args)
        finally:
            _compiling -= 1
            if not _compiling:  # a kernel's first call holds those of the kernels it calls
                _compile_seconds += time.perf_counter() - began

    def compile(self) -> Callable[..., Any]:
        if self.compiled is None:
            import numba

            # numba types a call to another kernel by its module's global: compiled first
            names = self.python.__globals__
            for name in self.python.__code__.co_names:
                if isinstance(names.get(name), _Kernel):
                    names[name] = names[name].compile()
            self.compiled = numba.njit(cache=True)(self.python)
            names[self.python.__name__] = self.compiled
        return self.compiled


def njit(kernel: F) -> F:
    """`numba.njit(cache=True)` of `kernel`, compiled at its first call."""
    return cast(F, _Kernel(kernel))

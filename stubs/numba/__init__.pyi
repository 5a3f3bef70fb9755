# The one part of numba the project uses, typed: a compiled function keeps its signature.
from collections.abc import Callable
from typing import Any, TypeVar

_F = TypeVar("_F", bound=Callable[..., Any])

def njit(*, cache: bool = ...) -> Callable[[_F], _F]: ...

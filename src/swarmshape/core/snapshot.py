"""A run's state as plain values: numpy arrays and JSON numbers and strings, never objects.

Saving a run means every stateful part (swarm, driver, strategy, queue, path fields, world)
writes a flat dict of named values; resuming reads them back through `Snapshot`'s typed
getters, which refuse anything of the wrong kind, shape or range with one clear message, so a
damaged or crafted state file can neither run code nor crash the restore.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from swarmshape.errors import InputError


class SnapshotError(InputError):
    """A state that cannot be restored; the message names the value that is wrong."""


def prefixed(prefix: str, values: Mapping[str, Any]) -> dict[str, Any]:
    """`values` under ``prefix.name`` keys, to nest one part's snapshot in another's."""
    return {f"{prefix}.{key}": value for key, value in values.items()}


class Snapshot:
    """Read-only, checked access to a flat dict of saved values."""

    def __init__(self, values: Mapping[str, Any], prefix: str = "") -> None:
        self._values = values
        self._prefix = prefix

    def part(self, name: str) -> Snapshot:
        """The values saved under ``name.``."""
        return Snapshot(self._values, f"{self._prefix}{name}.")

    def has(self, key: str) -> bool:
        return self._prefix + key in self._values

    def keys(self) -> list[str]:
        """Names in this part (without the prefix), direct children and deeper ones."""
        n = len(self._prefix)
        return [key[n:] for key in self._values if key.startswith(self._prefix)]

    def _get(self, key: str) -> Any:
        try:
            return self._values[self._prefix + key]
        except KeyError:
            raise self.error(key, "is missing") from None

    def error(self, key: str, problem: str) -> SnapshotError:
        return SnapshotError(f"damaged state: {self._prefix}{key} {problem}")

    def array(
        self,
        key: str,
        dtype: type | np.dtype,
        shape: tuple[int | None, ...],
        low: float | None = None,
        high: float | None = None,
        *,
        finite: bool | None = True,
    ) -> np.ndarray:
        """An array of exactly this dtype and shape (None: any length), values in
        ``[low, high]``, finite (or, with ``finite=False``, not NaN; with None, unchecked);
        a fresh writable copy."""
        value = self._get(key)
        if not isinstance(value, np.ndarray) or value.dtype != np.dtype(dtype):
            raise self.error(key, f"is not an array of {np.dtype(dtype)}")
        if value.ndim != len(shape) or any(
            want is not None and got != want for got, want in zip(value.shape, shape, strict=True)
        ):
            raise self.error(key, f"has shape {value.shape}, expected {shape}")
        if value.size and value.dtype.kind in "iuf" and finite is not None:
            if np.isnan(value).any() or (finite and not np.isfinite(value).all()):
                raise self.error(key, "holds a value that is not a finite number")
            if low is not None and value.min() < low:
                raise self.error(key, f"holds {value.min()}, below {low}")
            if high is not None and value.max() > high:
                raise self.error(key, f"holds {value.max()}, above {high}")
        return value.copy()

    def integer(self, key: str, low: int | None = None, high: int | None = None) -> int:
        value = self._get(key)
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.error(key, "is not a whole number")
        if (low is not None and value < low) or (high is not None and value > high):
            raise self.error(key, f"is {value}, outside [{low}, {high}]")
        return value

    def integers(
        self, key: str, count: int, low: int | None = None, high: int | None = None
    ) -> list[int]:
        """A list of exactly `count` whole numbers in ``[low, high]``."""
        value = self._get(key)
        whole = isinstance(value, list) and all(type(v) is int for v in value)
        if not whole or len(value) != count:
            raise self.error(key, f"is not a list of {count} whole numbers")
        if any((low is not None and v < low) or (high is not None and v > high) for v in value):
            raise self.error(key, f"holds a number outside [{low}, {high}]")
        return value

    def number(self, key: str, low: float | None = None, high: float | None = None) -> float:
        value = self._get(key)
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise self.error(key, "is not a number")
        value = float(value)
        if not np.isfinite(value) or (low is not None and value < low):
            raise self.error(key, f"is {value}, expected at least {low}")
        if high is not None and value > high:
            raise self.error(key, f"is {value}, expected at most {high}")
        return value

    def text(self, key: str) -> str:
        value = self._get(key)
        if not isinstance(value, str):
            raise self.error(key, "is not text")
        return value

    def plain(self) -> dict[str, Any]:
        """This part's direct values, by name (for reading a record of plain settings)."""
        return {key: self._values[self._prefix + key] for key in self.keys() if "." not in key}

    def value(self, key: str) -> Any:
        """A plain JSON value (number, text, list, mapping, or None), unchecked."""
        return self._get(key)


SCALARS = (bool, int, float, str, type(None))


def encode_attributes(owner: str, attributes: Mapping[str, Any]) -> dict[str, Any]:
    """A plug-in's attributes as saved values: numbers, text and arrays, and lists of either
    (numpy's scalars, ``np.int64(3)``, count as numbers).

    Anything else cannot go into a state file (it would need pickle), which is said plainly.
    """
    values: dict[str, Any] = {}
    for name, value in attributes.items():
        items = value if isinstance(value, list | tuple) else None
        if isinstance(value, (np.ndarray, *SCALARS)):
            values[name] = value
        elif isinstance(value, np.generic):
            values[name] = value.item()
        elif items is not None and all(isinstance(item, np.ndarray) for item in items):
            values[name] = {"arrays": len(items)}
            values |= {f"{name}.{i}": item for i, item in enumerate(items)}
        elif items is not None and all(isinstance(item, (*SCALARS, np.generic)) for item in items):
            values[name] = [_plain(item) for item in items]
        else:
            raise SnapshotError(
                f"{owner} keeps a {type(value).__name__} in self.{name}, which a state file "
                "cannot hold: keep numbers, text and numpy arrays (or lists of them), or "
                "define snapshot() and restore()"
            )
    return values


def _plain(item: Any) -> Any:
    return item.item() if isinstance(item, np.generic) else item


def decode_attributes(saved: Snapshot, fresh: Mapping[str, Any]) -> dict[str, Any]:
    """The attributes `encode_attributes` saved: every one, those a plug-in sets after it is
    made (in ``on_start``, say) too. One that a freshly made plug-in holds is checked against
    the kind of value it holds there."""
    stored = saved.keys()  # a Snapshot is no dict: it lists its names
    names = sorted({key for key in stored if "." not in key} | set(fresh))
    restored: dict[str, Any] = {}
    for name in names:
        if name not in fresh:
            restored[name] = _decode_any(saved, name)
            continue
        value = fresh[name]
        if isinstance(value, np.ndarray):
            restored[name] = saved.array(name, value.dtype, (None,) * value.ndim, finite=None)
        elif isinstance(value, list | tuple):
            restored[name] = _decode_list(saved, name)
        elif isinstance(value, np.generic):
            got = saved.value(name)
            if not isinstance(got, SCALARS) or isinstance(got, str | None):
                raise saved.error(name, f"is a {type(got).__name__}, not a number")
            restored[name] = type(value)(got)
        else:
            got = saved.value(name)
            if type(got) is not type(value) and not (isinstance(value, float) and type(got) is int):
                raise saved.error(name, f"is a {type(got).__name__}, not a {type(value).__name__}")
            restored[name] = got
    return restored


def _decode_any(saved: Snapshot, name: str) -> Any:
    """An attribute a fresh plug-in does not hold yet, as `encode_attributes` saved it."""
    got = saved.value(name)
    if isinstance(got, np.ndarray):
        return _any_array(saved, name)
    if isinstance(got, dict | list):
        return _decode_list(saved, name)
    if not isinstance(got, SCALARS):
        raise saved.error(name, "is not a number, text, an array or a list of them")
    return got


def _decode_list(saved: Snapshot, name: str) -> list[Any]:
    got = saved.value(name)
    if isinstance(got, dict):
        arrays = got.get("arrays")
        if not isinstance(arrays, int) or isinstance(arrays, bool) or arrays < 0:
            raise saved.error(name, "is not a list")
        return [_any_array(saved, f"{name}.{i}") for i in range(arrays)]
    if not isinstance(got, list) or not all(isinstance(item, SCALARS) for item in got):
        raise saved.error(name, "is not a list of numbers or text")
    return got


def _any_array(saved: Snapshot, key: str) -> np.ndarray:
    value = saved.value(key)
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
        raise saved.error(key, "is not an array of numbers")
    return saved.array(key, value.dtype, (None,) * value.ndim, finite=None)

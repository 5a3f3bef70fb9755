"""Declared options: each setting's name, kind, default, range and help, written once.

A dataclass field made with `option` carries everything its readers need: the run's settings
(`swarmshape.config.RunConfig`), the knobs of the core's physics (`Limits`, `Senses`), and every
plug-in's own ``Options``. From that one declaration come the checks of plain values (a TOML
file, a saved run, Python keywords: `Spec.check`), of text (a command line: `Spec.parse`), the
command line's flags, the README's table, and the listing of ``swarmshape strategies NAME``.

Errors are `SettingError`: they name the setting, never a command-line flag, and the face that
read the value (the command line, a scenario file) says where it came from.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmshape.errors import InputError, SettingError

PLUGIN_KINDS = frozenset({"central", "local"})
"""The two kinds of plug-in (see `swarmshape.core.plugin`); a setting lists those that read it."""


def _same(value: Any) -> Any:
    return value


@dataclass(frozen=True)
class Kind:
    """What values a setting takes: `describe` names them in messages, `coerce` takes a plain
    value (or raises ValueError), `parse` takes text."""

    describe: str
    coerce: Callable[[Any], Any]
    parse: Callable[[str], Any]
    plain: Callable[[Any], Any] = _same
    """The value as plain data (for JSON, TOML and CSV)."""
    metavar: str = "VALUE"
    """How a command line's help shows a value of this kind."""


LARGEST = 2**63 - 1
"""The largest whole number a setting takes: robots' memory and messages are 64-bit integers,
and numpy refuses a larger one in a comparison with them (an `OverflowError` mid-run)."""


def _integer(value: Any) -> int:
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        raise ValueError
    if not -LARGEST - 1 <= value <= LARGEST:
        raise OverflowError
    return int(value)


def _number(value: Any) -> float:
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.number):
        raise ValueError
    if isinstance(value, complex | np.complexfloating):
        raise ValueError
    number = float(value)
    if not math.isfinite(number):
        raise ValueError
    return number


def _flag(value: Any) -> bool:
    if not isinstance(value, bool | np.bool_):
        raise ValueError
    return bool(value)


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError
    return value


def _ascii(text: str) -> str:
    """Numbers are written in ASCII digits: ``int`` would take a superscript's neighbours
    (Arabic-Indic digits) but not the superscript, which only confuses."""
    if not text.isascii():
        raise ValueError
    return text.strip()


TRUE, FALSE = ("true", "yes", "on", "1"), ("false", "no", "off", "0")


def _parse_flag(text: str) -> bool:
    word = text.strip().lower()
    if word in TRUE or word in FALSE:
        return word in TRUE
    raise ValueError


INTEGER = Kind("a whole number", _integer, lambda text: int(_ascii(text)), metavar="N")
NUMBER = Kind("a number", _number, lambda text: _number(float(_ascii(text))), metavar="X")
FLAG = Kind("true or false", _flag, _parse_flag)
TEXT = Kind("text", _text, str, metavar="NAME")
KINDS = {bool: FLAG, int: INTEGER, float: NUMBER, str: TEXT}
"""The kind a default of each type implies, so most options need not name theirs."""


@dataclass(frozen=True)
class Spec:
    """One declared setting: what it is called, takes, defaults to and means."""

    name: str
    kind: Kind
    default: Any
    help: str = ""
    at_least: float | None = None
    at_most: float | None = None
    below: float | None = None
    choices: tuple[Any, ...] | None = None
    readers: frozenset[str] = PLUGIN_KINDS
    """The plug-in kinds that read it: a run of another kind warns that it changes nothing."""
    extra: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    """What a particular table adds (the run settings' command-line group, say)."""

    @property
    def nullable(self) -> bool:
        """None means "not set" (the default decides later)."""
        return self.default is None

    def check(self, value: Any) -> Any:
        """`value` as this setting's kind, within its range, or a `SettingError`."""
        if value is None and self.nullable:
            return None
        try:
            value = self.kind.coerce(value)
        except InputError:  # a kind that says itself what is wrong (a list of fault events)
            raise
        except OverflowError:
            fits = f"{self.describe()}, at most {LARGEST:,}"
            raise self.error(f"must be {fits}, got {_shown(value)}") from None
        except (ValueError, TypeError):
            raise self.error(f"must be {self.describe()}, got {_shown(value)}") from None
        if not self.allows(value):
            raise self.error(f"must be {self.describe()}, got {_shown(value)}")
        return value

    def parse(self, text: str) -> Any:
        """Text (a command line's) as this setting's value, or a `SettingError`."""
        try:
            value = self.kind.parse(text)
        except (ValueError, TypeError, OverflowError):
            raise self.error(f"must be {self.describe()}, got {text!r}") from None
        return self.check(value)

    def allows(self, value: Any) -> bool:
        if self.choices is not None and value not in self.choices:
            return False
        low, high = self.at_least, self.at_most
        return not (
            (low is not None and value < low)
            or (high is not None and value > high)
            or (self.below is not None and value >= self.below)
        )

    def describe(self) -> str:
        """What it takes, in words: "a number from 1 to 16", "one of a, b"."""
        if self.choices is not None:
            return "one of " + ", ".join(map(str, self.choices))
        return f"{self.kind.describe}{self.range_text()}"

    def range_text(self) -> str:
        low, high, below = self.at_least, self.at_most, self.below
        if low is not None and high is not None:
            return f" from {_num(low)} to {_num(high)}"
        if low is not None and below is not None:
            return f" from {_num(low)} up to (not including) {_num(below)}"
        if low is not None:
            return f" of {_num(low)} or more"
        if high is not None:
            return f" of {_num(high)} or less"
        if below is not None:
            return f" below {_num(below)}"
        return ""

    def error(self, problem: str) -> SettingError:
        return SettingError(self.name, problem)


def option(
    default: Any,
    help: str = "",
    *,
    kind: Kind | None = None,
    name: str | None = None,
    at_least: float | None = None,
    at_most: float | None = None,
    below: float | None = None,
    choices: tuple[Any, ...] | None = None,
    readers: frozenset[str] = PLUGIN_KINDS,
    **extra: Any,
) -> Any:
    """A dataclass field declaring a setting (see `Spec`). Its kind follows from the default's
    type unless given; `name` is the setting's public name when it differs from the field's."""
    if kind is None:
        kind = KINDS.get(type(default))
        if kind is None:
            raise TypeError(f"option with default {default!r} needs kind=")
    meta = {
        "option": {
            "name": name,
            "kind": kind,
            "help": help,
            "at_least": at_least,
            "at_most": at_most,
            "below": below,
            "choices": choices,
            "readers": readers,
            "extra": extra,
        }
    }
    if isinstance(default, list | dict | set):
        return dataclasses.field(default_factory=lambda: type(default)(default), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def same_as(owner: type | Spec, field_name: str | None = None, **changes: Any) -> Any:
    """A field declaring the same setting as a core knob (a field of `owner`, or a `Spec`),
    with `changes` to what a table adds (its readers, its command-line group)."""
    spec = owner if isinstance(owner, Spec) else spec_of(owner, field_name or "")
    extra = {**spec.extra, **changes}
    readers = extra.pop("readers", spec.readers)
    return option(
        spec.default,
        spec.help,
        kind=spec.kind,
        name=spec.name,
        at_least=spec.at_least,
        at_most=spec.at_most,
        below=spec.below,
        choices=spec.choices,
        readers=readers,
        **extra,
    )


@dataclass(frozen=True)
class _Field:
    field: str
    spec: Spec


def _specs(cls: type) -> list[_Field]:
    return [_Field(field.name, _spec(cls, field)) for field in dataclasses.fields(cls)]


def _spec(cls: type, field: dataclasses.Field[Any]) -> Spec:
    meta = dict(field.metadata.get("option", {}))
    default = field.default
    if default is dataclasses.MISSING and field.default_factory is not dataclasses.MISSING:
        default = field.default_factory()
    if not meta:  # a plain field of a user's Options: its default's type is its kind
        kind = KINDS.get(type(default))
        if kind is None:
            raise TypeError(
                f"{cls.__name__}.{field.name}: an option needs a default that is a bool, "
                "int, float or str, or an option(...) field naming its kind"
            )
        meta = {"kind": kind}
    meta["name"] = meta.get("name") or field.name
    return Spec(default=default, **meta)


def spec_of(cls: type, field_name: str) -> Spec:
    """The spec of one field of `cls` (its other fields need not be settings)."""
    field = next(field for field in dataclasses.fields(cls) if field.name == field_name)
    return _spec(cls, field)


def specs(cls: type) -> tuple[Spec, ...]:
    """The settings a dataclass declares, in order."""
    return tuple(found.spec for found in _specs(cls))


def documented(cls: type) -> type:
    """A dataclass of settings whose docstring ends with every setting it declares (name,
    meaning, what it takes, default): ``help()`` and the API reference then list them all, from
    the declarations themselves."""
    lines = []
    for spec in specs(cls):
        told = [spec.help, spec.describe()]
        if spec.default not in (None, (), {}) and spec.kind is not FLAG:
            told.append(f"default {plain(spec.default)}")
        lines.append(f"- `{spec.name}`: " + "; ".join(part for part in told if part))
    cls.__doc__ = inspect.cleandoc(cls.__doc__ or "") + "\n\nIts settings:\n\n" + "\n".join(lines)
    return cls


def checked(instance: Any) -> None:
    """Check every field of a dataclass instance against its spec, in place (for
    ``__post_init__``): values are coerced to their kinds, or a `SettingError` names the one
    that is not."""
    for found in _specs(type(instance)):
        value = found.spec.check(getattr(instance, found.field))
        object.__setattr__(instance, found.field, value)


def from_values(cls: type, values: Mapping[str, Any], owner: str) -> Any:
    """An instance of `cls` (a dataclass of options) from plain values by name; an unknown
    name is a `SettingError` that lists those `owner` takes."""
    by_name = {found.spec.name: found for found in _specs(cls)}
    given = {}
    for name, value in values.items():
        if name not in by_name:
            raise SettingError(name, f"is not an option of {owner}; {takes(cls, owner)}")
        given[by_name[name].field] = by_name[name].spec.check(value)
    return cls(**given)


def takes(cls: type, owner: str) -> str:
    names = [spec.name for spec in specs(cls)]
    if not names:
        return f"{owner} takes no options"
    return f"{owner} takes {', '.join(names)}"


def values_of(instance: Any) -> dict[str, Any]:
    """An options instance as plain values by setting name (for files and sweep rows)."""
    return {found.spec.name: getattr(instance, found.field) for found in _specs(type(instance))}


def _num(value: float) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if value > 2**31 and (value + 1).bit_count() == 1:  # a type's limit: 2**63 - 1
        return f"2**{(value + 1).bit_length() - 1} - 1"
    return f"{value:,}"


def plain(value: Any) -> str:
    """A value as help texts print it: 0.5, 500,000, optimal."""
    if isinstance(value, float):
        return f"{value:g}"
    return f"{value:,}" if isinstance(value, int) and not isinstance(value, bool) else str(value)


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."

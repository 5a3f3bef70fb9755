"""What a run is: `RunConfig`, the one table of run settings, and `configure`, which fills it.

Every run setting is one field of `RunConfig`, declared once with its kind, default, range, a
line of help and the plug-in kinds that read it (`swarmshape.core.options.option`). The command
line's flags, the keys a scenario and a sweep may set, the checks of a saved run's settings and
the README's table of options are all made from these fields, so a new setting is one
declaration. A plug-in's own settings are its ``Options`` (see `swarmshape.core.plugin`); a run
carries their values in `RunConfig.options`, checked against the plug-in it names.

    config = configure("shapes/star.png", seed=1, max_speed=1.0)   # defaults < file < these
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarmshape import strategies
from swarmshape.core.faults import FAILURE_RATE, FaultEvent, events_from_values
from swarmshape.core.motion import Limits
from swarmshape.core.options import (
    INTEGER,
    TEXT,
    Kind,
    Spec,
    documented,
    from_values,
    option,
    same_as,
    specs,
    values_of,
)
from swarmshape.core.perception import Senses
from swarmshape.core.swarm import Params
from swarmshape.core.world import START_LAYOUTS
from swarmshape.errors import InputError, SettingError, SettingWarning
from swarmshape.io.bitmap import DEFAULT_THRESHOLD
from swarmshape.io.scenario import group_settings, scenario_settings

LOCAL = frozenset({"local"})
"""Settings only local programs read (how well their robots sense and talk)."""


def _path(value: Any) -> Path:
    if not isinstance(value, str | Path) or "\0" in str(value) or str(value) == "":
        raise ValueError
    return Path(value)


def _pair(value: Any) -> tuple[int, int]:
    if isinstance(value, str):
        value = value.lower().split("x")
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise ValueError
    # each part as text or as a number: a file's list may hold both (the fuzz: ["0", 20])
    value = [INTEGER.parse(part) if isinstance(part, str) else part for part in value]
    width, height = (INTEGER.coerce(v) for v in value)
    if width < 1 or height < 1:
        raise ValueError
    return width, height


def start_of(value: Any) -> str | Path:
    """A start layout by name, or the path of a CSV of start cells (text naming a ``.csv``
    or an existing file is one); anything else raises ValueError."""
    if isinstance(value, Path):
        return value
    if not isinstance(value, str):
        raise ValueError
    if value in START_LAYOUTS:
        return value
    if Path(value).suffix.lower() == ".csv" or _names_a_file(value):
        return Path(value)
    raise ValueError


def _names_a_file(text: str) -> bool:
    """Whether `text` names a file that exists: a name the system refuses outright (a NUL in
    it, or too long: a state file's config can hold anything) names none."""
    try:
        return Path(text).exists()
    except (OSError, ValueError):
        return False


def _faults(value: Any) -> tuple[FaultEvent, ...]:
    return events_from_values(value, "faults")


def _options(value: Any) -> dict[str, Any]:
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise ValueError
    return dict(value)


def _no_text(text: str) -> Any:
    raise ValueError


PATH = Kind("a file name", _path, _path, str, "FILE")
PAIR = Kind("two whole numbers of 1 or more, WIDTHxHEIGHT", _pair, _pair, list, "WxH")
START = Kind(
    f"{', '.join(START_LAYOUTS)} or a CSV file of start cells", start_of, start_of, str, "WHERE"
)
FAULTS = Kind(
    "a list of fault events", _faults, _no_text, lambda events: [e.values() for e in events]
)
OPTIONS = Kind("a table of the plug-in's options", _options, _no_text, dict)


@documented
@dataclass(frozen=True)
class RunConfig:
    """Everything that decides a run. The defaults here are the project's only defaults.

    Each field declares one setting; ``group`` says where the command line lists its flag
    (``flag=False``: the command line spells it its own way)."""

    shape: Path | None = option(
        None,
        "an image (PNG, GIF, BMP, JPEG, WebP) or a .toml scenario; default the bundled horseshoe",
        kind=PATH,
        flag=False,
        cli="`PATH`, the first argument",
        files="a group's `shape`; sweeps: `shapes`",
    )
    strategy: str = option(
        "optimal",
        "who goes where: optimal, greedy, random, paper, a local program (swarmshape "
        "strategies lists them), or your own path/to/file.py:Class or package.module:Class",
        group="run",
        files="`strategy`; sweeps: `strategies`",
    )
    seed: int | None = option(
        None,
        "the run's random seed; default a fresh one, printed. Same seed, same run, byte for byte",
        kind=INTEGER,
        at_least=0,
        at_most=2**63 - 1,
        group="run",
        files="`seed`; sweeps: `seeds`, a count or a list",
    )
    agents: int | None = option(
        None,
        "number of robots; default one per cell. Fewer than cells shrinks the shape to the "
        "largest scale that fits; more leaves spare robots outside the shape",
        kind=INTEGER,
        at_least=1,
        group="run",
        files="`agents`, also per group; sweeps: 0 is one per cell",
    )
    options: dict[str, Any] = option(
        {},
        "the strategy's own options, by name (swarmshape strategies NAME lists them)",
        kind=OPTIONS,
        flag=False,
        cli="`--set NAME=VALUE`, repeatable",
        files="`[options]`; sweeps: `options.NAME`",
    )
    cells: int | None = option(
        None,
        "cells across the shape's long side: larger images are area-averaged down, smaller "
        "ones grown; default the fewest from 32 up that keep the picture's pieces and holes "
        "with an IoU of at least 0.5 (a picture of at most 32 pixels: its own size)",
        kind=INTEGER,
        at_least=1,
        group="image loading",
    )
    threshold: float = option(
        DEFAULT_THRESHOLD,
        "ink is darker than this luminance (0 to 1) on a light background; a dark background "
        "is detected from the border",
        at_least=0.0,
        at_most=1.0,
        group="image loading",
    )
    invert: bool = option(False, "the ink is the light part", group="image loading")
    fit: str | None = option(
        None,
        "agents: size the shape to --agents (as many cells as robots, or just fewer)",
        kind=TEXT,
        choices=("agents",),
        group="image loading",
    )
    arena: tuple[int, int] | None = option(
        None,
        "arena size in cells, WIDTHxHEIGHT; default automatic, five free cells per robot",
        kind=PAIR,
        group="simulation",
    )
    start: str | Path | None = option(
        None,
        "where robots start: scatter (random free cells, the default), packed (a block "
        "against the seeds, as in the Kilobot self-assembly experiments), or a CSV of start "
        "cells (columns x,y, one row per robot)",
        kind=START,
        group="simulation",
    )
    max_speed: float = same_as(Limits, "max_speed", group="simulation")
    max_accel: float = same_as(Limits, "max_accel", group="simulation")
    speed_variation: float = same_as(Params, "speed_variation", group="simulation")
    max_steps: int = option(
        500_000, "stop after this many steps in all", at_least=0, group="simulation"
    )
    sense_radius: float = same_as(Senses, "radius", readers=LOCAL, group="local programs")
    distance_noise: float = same_as(Senses, "distance_noise", readers=LOCAL, group="local programs")
    msg_loss: float = same_as(Senses, "msg_loss", readers=LOCAL, group="local programs")
    faults: tuple[FaultEvent, ...] = option(
        (),
        "robots removed or stalled at given steps (see swarmshape.core.faults)",
        kind=FAULTS,
        flag=False,
        cli="`--fail`, `--fail-region`, `--stall` (see Faults)",
        files="`[[faults]]`; sweeps: `fail`, `stall`, `fail_region`",
    )
    failure_rate: float = same_as(FAILURE_RATE, group="faults")
    on_loss: str = same_as(Params, "on_loss", group="faults")

    def __post_init__(self) -> None:
        for spec in SETTINGS:
            object.__setattr__(self, spec.name, spec.check(getattr(self, spec.name)))
        if self.fit == "agents" and self.agents is None:
            raise SettingError("fit", "agents sizes the shape to the robots: give their number too")
        Limits(self.max_speed, self.max_accel)  # the one rule between two settings
        if self.options and not strategies.is_code(self.strategy):
            object.__setattr__(self, "options", values_of(plugin_options(self)))

    def senses(self) -> Senses:
        """How well a local program's robots sense and talk."""
        return Senses(self.sense_radius, self.distance_noise, self.msg_loss)

    def params(self) -> Params:
        """The physics of the run, as the swarm takes it."""
        return Params(
            Limits(self.max_speed, self.max_accel),
            self.senses(),
            speed_variation=self.speed_variation,
            on_loss=self.on_loss,
        )

    @property
    def shape_path(self) -> Path:
        return self.shape if self.shape is not None else bundled_shapes() / DEFAULT_SHAPE

    def values(self) -> dict[str, Any]:
        """This description as plain values (paths as text, the arena as a list)."""
        return {
            spec.name: None if value is None else spec.kind.plain(value)
            for spec in SETTINGS
            for value in [getattr(self, spec.name)]
        }

    @classmethod
    def from_values(cls, values: Mapping[str, Any], source: str) -> RunConfig:
        """A description from plain values (a saved run's), each checked for its kind."""
        try:
            return from_values(cls, values, "a run")
        except InputError as error:
            raise InputError(f"{source}: {error}") from None

    def seeded(self) -> RunConfig:
        """This description with a concrete seed (a fresh one if it had none)."""
        if self.seed is not None:
            return self
        return dataclasses.replace(self, seed=int(np.random.SeedSequence().generate_state(1)[0]))


SETTINGS: tuple[Spec, ...] = specs(RunConfig)
"""Every run setting, in the table's order."""

DEFAULT_SHAPE = "horseshoe.png"


def setting(name: str) -> Spec:
    """The run setting called `name`."""
    return next(spec for spec in SETTINGS if spec.name == name)


def plugin_options(config: RunConfig) -> Any:
    """The chosen plug-in's ``Options`` filled with `config.options`, every value checked (a
    value given as command-line text is parsed first, see `CommandLine`)."""
    cls = strategies.get(config.strategy)
    by_name = {spec.name: spec for spec in specs(cls.Options)}
    given = {}
    for name, value in config.options.items():
        if name in by_name and isinstance(value, CommandLine):
            value = by_name[name].parse(value)
        given[name] = value
    try:
        return from_values(cls.Options, given, config.strategy)
    except SettingError as error:
        owners = strategies.owners_of(error.setting) if error.setting not in by_name else []
        if owners:
            raise SettingError(
                error.setting, f"is an option of {', '.join(owners)}, not of {config.strategy}"
            ) from None
        raise


class CommandLine(str):
    """An option's value as text typed on a command line (``--set NAME=VALUE``), to be read
    by the option's own kind: 12 for a whole number, true for a flag."""


def configure(shape: str | Path | None = None, **given: Any) -> RunConfig:
    """A complete description: `RunConfig`'s defaults, overridden by the settings of a scenario
    file, overridden by `given` (settings left at None count as not given), with a seed.
    Options merge name by name: ``options={"order": "random"}`` keeps the file's others."""
    path = None if shape is None else Path(shape)
    from_file = {} if path is None else scenario_settings(path)
    if from_file:
        try:
            _known(from_file)
            _data_only(from_file)
            RunConfig(shape=path, **from_file)
        except InputError as error:  # say which file holds the value
            raise InputError(f"{path}: {error}") from None
    for index, group in enumerate([] if path is None else group_settings(path)):
        try:
            RunConfig(shape=path, **group)
        except InputError as error:
            raise InputError(f"{path}: groups[{index}].{error}") from None
    chosen = {key: value for key, value in given.items() if value is not None}
    _known(chosen)
    file_options = from_file.get("options", {})
    other = chosen.get("strategy", from_file.get("strategy")) != from_file.get("strategy")
    if file_options and other:  # the file's options are its strategy's
        names = ", ".join(file_options)
        problem = f"{names} in {path} {'are' if len(file_options) > 1 else 'is'} for "
        problem += f"{from_file.get('strategy', RunConfig.strategy)}: ignored"
        warnings.warn(SettingWarning("options", problem), stacklevel=2)
        file_options = {}
    options = {**file_options, **chosen.get("options", {})}
    settings = {**from_file, **chosen, "options": options}
    config = RunConfig(shape=path, **settings)
    _warn_unread(config, set(from_file) | set(chosen))
    return config.seeded()


def option_of(name: str) -> str | None:
    """ "an option of paper" if `name` is not a run setting but some plug-in's option (so a
    face can say where it goes), else None."""
    owners = strategies.owners_of(name)
    return f"an option of {', '.join(owners)}" if owners else None


def _known(settings: Mapping[str, Any]) -> None:
    """Every name is a run setting; a plug-in's option given as one says where it goes."""
    names = {spec.name for spec in SETTINGS}
    for name in settings:
        if name in names:
            continue
        if option_of(name):
            raise SettingError(name, f"is {option_of(name)}, not a run setting: set it as one")
        known = ", ".join(spec.name for spec in SETTINGS)
        raise SettingError(name, f"is not a run setting; the run settings are {known}")


def _data_only(settings: Mapping[str, Any]) -> None:
    """A file of settings is data: it names registered strategies and start layouts only,
    never code or other files."""
    strategy = settings.get("strategy")
    if isinstance(strategy, str) and strategies.is_code(strategy):
        raise SettingError(
            "strategy",
            f"= {strategy!r} points at code, and a file of settings is data: name a registered "
            "or installed strategy, or give --strategy on the command line",
        )
    start = settings.get("start")
    if start is not None and start not in START_LAYOUTS:
        raise SettingError(
            "start",
            f"= {start!r}; choose {', '.join(START_LAYOUTS)} (a CSV of start cells is given "
            "with --start on the command line)",
        )


def _warn_unread(config: RunConfig, given: set[str]) -> None:
    """Say so when a setting was given that the chosen plug-in never reads."""
    kind = strategies.get(config.strategy).kind
    for spec in SETTINGS:
        if spec.name in given and kind not in spec.readers:
            readers = " and ".join(f"{k} plug-ins" for k in sorted(spec.readers))
            problem = f"is read only by {readers}; {config.strategy} is a {kind} one: it is ignored"
            warnings.warn(SettingWarning(spec.name, problem), stacklevel=3)


def bundled_shapes() -> Path:
    """The shipped shapes: inside an installed wheel, or the source checkout's shapes/."""
    from importlib import resources

    installed = resources.files("swarmshape") / "shapes"
    if installed.is_dir():
        return Path(str(installed))
    return Path(__file__).resolve().parents[2] / "shapes"

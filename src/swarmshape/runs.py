"""One way to describe, build and run a swarm: `RunConfig`, `configure`, `build`, `Runner`.

Every entry point goes through here: the command line, sweeps, the window's restart, the
benchmark and the soak. A run is a typed description plus a seed::

    config = configure("shapes/star.png", seed=1)      # defaults < scenario file < these
    swarm = build(config)
    run(swarm, max_steps=config.max_steps)

Observers (recorders, traces, progress bars) see the swarm after every step and are closed at
the end; the loop is `Runner`, which the window drives one step at a time.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from swarmshape import strategies
from swarmshape.core.faults import FaultEvent, Faults, check_rate, events_from_values
from swarmshape.core.local import Program
from swarmshape.core.motion import Limits
from swarmshape.core.perception import Senses
from swarmshape.core.snapshot import Snapshot, prefixed
from swarmshape.core.steering import Strategy
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import START_LAYOUTS, World, build_world, packed_start
from swarmshape.errors import InputError
from swarmshape.io.bitmap import DEFAULT_THRESHOLD, ShapeWarning
from swarmshape.io.checkpoint import load_state, save_state
from swarmshape.io.scenario import ImageOptions, load_scenario, read_start_cells, scenario_settings
from swarmshape.strategies.fill_order import DEFAULT_ORDER, ORDERS

DEFAULT_SHAPE = "horseshoe.png"


@dataclass(frozen=True)
class RunConfig:
    """Everything that decides a run. The defaults here are the project's only defaults."""

    shape: Path | None = None
    """An image or a ``.toml`` scenario; None is the bundled horseshoe."""
    strategy: str = "optimal"
    """A registered name, an installed one, or ``package.module:Class``."""
    order: str = DEFAULT_ORDER
    """The paper strategy's fill order (other strategies ignore it)."""
    seed: int | None = None
    """None draws a fresh seed when the swarm is built; the swarm records it."""
    agents: int | None = None
    """Robots of a one-group run; None is one per cell of the shape."""
    cells: int | None = None
    """Cells across the shape's long side; None is the image's own size, at most 32."""
    threshold: float = DEFAULT_THRESHOLD
    invert: bool = False
    arena: tuple[int, int] | None = None
    """Arena size in cells; None sizes it to the shape and the robots."""
    max_speed: float = Limits.max_speed
    max_accel: float = Limits.max_accel
    max_steps: int = 500_000
    start: Path | str | None = None
    """Where robots start: ``"packed"`` (a block against the seeds), ``"scatter"`` (random free
    cells, as None), or a CSV of start cells (columns x,y)."""
    fit: str | None = None
    """"agents": size the shape to the robots (as many cells as there are robots, or fewer)."""
    speed_variation: float = 0.0
    """Each robot's top speed is ``max_speed`` times a factor drawn from ``[1 - this, 1]``."""
    sense_radius: float = Senses.radius
    """Local programs: how far, in cells, a robot senses and hears its neighbours."""
    distance_noise: float = Senses.distance_noise
    msg_loss: float = Senses.msg_loss
    faults: tuple[FaultEvent, ...] = ()
    """Fault events: robots removed or stalled at given steps (see `swarmshape.core.faults`)."""
    failure_rate: float = 0.0
    """Chance per robot per step that it fails and is removed."""

    def __post_init__(self) -> None:
        if self.seed is not None and not 0 <= self.seed < 2**63:
            raise InputError(f"--seed must be a whole number from 0 to 2**63 - 1, got {self.seed}")
        if self.order not in ORDERS:
            raise InputError(f"unknown order {self.order!r}; choose one of {', '.join(ORDERS)}")
        if self.max_steps < 0:
            raise InputError(f"--max-steps must be 0 or more, got {self.max_steps}")
        if self.fit not in FITS:
            raise InputError(f"unknown --fit {self.fit!r}; choose {', '.join(map(str, FITS[1:]))}")
        if self.fit == "agents" and self.agents is None:
            raise InputError("--fit agents sizes the shape to --agents N; give that number")
        object.__setattr__(self, "start", start_of(self.start))
        Limits(self.max_speed, self.max_accel)  # checks them
        Params(speed_variation=self.speed_variation)
        self.senses()
        object.__setattr__(self, "faults", events_from_values(self.faults, "faults"))
        object.__setattr__(self, "failure_rate", check_rate(self.failure_rate))

    def senses(self) -> Senses:
        """How well a local program's robots sense and talk."""
        return Senses(self.sense_radius, self.distance_noise, self.msg_loss)

    @property
    def shape_path(self) -> Path:
        return self.shape if self.shape is not None else bundled_shapes() / DEFAULT_SHAPE

    def values(self) -> dict[str, Any]:
        """This description as plain values (paths as text, the arena as a list)."""
        plain = dataclasses.asdict(self)
        for name in ("shape", "start"):
            plain[name] = None if plain[name] is None else str(plain[name])
        plain["arena"] = None if self.arena is None else list(self.arena)
        plain["faults"] = [event.values() for event in self.faults]
        return plain

    @classmethod
    def from_values(cls, values: Mapping[str, Any], source: str) -> RunConfig:
        """A description from plain values (a saved run's), each checked for its type."""
        unknown = sorted(set(values) - set(KINDS))
        if unknown:
            raise InputError(f"{source}: unknown run setting {unknown[0]!r}")
        unset = sorted(name for name, value in values.items() if value is None)
        unset = [name for name in unset if name not in NULLABLE]
        if unset:
            raise InputError(f"{source}: {unset[0]} must have a value, got none")
        checked = {
            name: _typed(value, KINDS[name], f"{source}: {name}") for name, value in values.items()
        }
        return cls(**checked)

    def seeded(self) -> RunConfig:
        """This description with a concrete seed (a fresh one if it had none)."""
        if self.seed is not None:
            return self
        return dataclasses.replace(self, seed=int(np.random.SeedSequence().generate_state(1)[0]))


FITS = (None, "agents")

NULLABLE = {field.name for field in dataclasses.fields(RunConfig) if field.default is None}
"""Settings that may be None (unset); for the others None is a damaged value."""

KINDS = {"shape": Path, "strategy": str, "order": str, "seed": int, "agents": int, "cells": int,
         "threshold": float, "invert": bool, "arena": tuple, "max_speed": float, "max_accel": float,
         "max_steps": int, "start": Path, "fit": str, "speed_variation": float,
         "sense_radius": float, "distance_noise": float, "msg_loss": float, "faults": list,
         "failure_rate": float}  # fmt: skip
"""The kind of value each `RunConfig` field takes (None is allowed where the default is None)."""


def _typed(value: Any, kind: type, where: str) -> Any:
    """`value` as `kind`, or a one-line error: plain values may come from any file."""
    if value is None:
        return None
    if kind is Path and isinstance(value, str) and value in START_LAYOUTS:
        return value
    if kind is Path and isinstance(value, str | Path):
        return Path(value)
    if kind is tuple:
        pair = isinstance(value, list | tuple) and len(value) == 2
        if pair and all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            return (value[0], value[1])
        raise InputError(f"{where} must be two whole numbers [width, height], got {value!r}")
    if kind is list:
        return events_from_values(value, where)
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if isinstance(value, kind) and (kind is bool or not isinstance(value, bool)):
        return value
    raise InputError(f"{where} must be {kind.__name__}, got {value!r}")


def start_of(value: str | Path | None) -> str | Path | None:
    """A start layout by name, or the path of a CSV of start cells (text naming a ``.csv``
    or an existing file is one); a misspelt name is one clear error."""
    if value is None or isinstance(value, Path) or value in START_LAYOUTS:
        return value
    if Path(value).suffix.lower() == ".csv" or Path(value).exists():
        return Path(value)
    raise InputError(f"unknown --start {value!r}; choose {', '.join(START_LAYOUTS)} or a CSV file")


def configure(shape: str | Path | None = None, **given: Any) -> RunConfig:
    """A complete description: `RunConfig`'s defaults, overridden by the settings of a scenario
    file, overridden by `given` (options left at None count as not given), with a seed."""
    path = None if shape is None else Path(shape)
    from_file = {} if path is None else scenario_settings(path)
    try:
        RunConfig(shape=path, **from_file)
    except InputError as error:  # say which file holds the value
        raise InputError(f"{path}: {error}") from None
    chosen = {key: value for key, value in given.items() if value is not None}
    unknown = sorted(set(chosen) - {f.name for f in dataclasses.fields(RunConfig)})
    if unknown:
        raise InputError(f"unknown run option {unknown[0]!r}")
    return RunConfig(shape=path, **{**from_file, **chosen}).seeded()


def registered_strategy(name: str) -> None:
    """Refuse, up front, a strategy that is not registered or installed: files of settings
    (scenarios, sweeps) are data and never name code."""
    if strategies.is_code(name):
        raise InputError(f"strategy {name!r} points at code; name a registered or installed one")
    strategies.get(name)


def bundled_shapes() -> Path:
    """The shipped shapes: inside an installed wheel, or the source checkout's shapes/."""
    installed = resources.files("swarmshape") / "shapes"
    if installed.is_dir():
        return Path(str(installed))
    return Path(__file__).resolve().parents[2] / "shapes"


def load_world(config: RunConfig) -> World:
    """The scenario's groups, fitted to their robots and placed in the arena."""
    path = config.shape_path
    image = ImageOptions(config.cells, config.threshold, config.invert)
    scenario = load_scenario(path, image, config.agents if config.fit == "agents" else None)
    specs = list(scenario.groups)
    if config.agents is not None:
        if len(specs) > 1:
            raise InputError("--agents applies to one shape; set agents per group in the scenario")
        specs[0] = dataclasses.replace(specs[0], agents=config.agents)
    grows = not strategies.is_code(config.strategy) and getattr(
        strategies.get(config.strategy), "grows_from_seeds", False
    )  # user code is loaded once, when the run starts
    if grows:
        specs = [dataclasses.replace(spec, shape=spec.shape.seeded()) for spec in specs]
    packed = config.start == "packed"
    world = build_world(specs, config.arena or scenario.arena, scenario.name, packed)
    cells = len(world.targets)
    if world.agents > 1.5 * cells and config.fit is None:
        warnings.warn(
            f"{world.agents:,} robots for a {cells:,}-cell shape: {world.agents - cells:,} "
            "will wait outside it; --fit agents sizes the shape to the robots",
            ShapeWarning,
            stacklevel=2,
        )
    if not grows:
        return world
    if config.faults or config.failure_rate:
        warnings.warn(
            f"{config.strategy} does not repair the shape: joined robots never move again, so "
            "cells that faults empty inside the structure stay empty",
            ShapeWarning,
            stacklevel=2,
        )
    for group in world.groups:
        if not group.shape.is_solid:
            warnings.warn(
                f"shape {group.name!r} has a hole or a part apart from its seeds, and "
                f"{config.strategy} cannot form those (robots join only the edge of what is "
                "built, outward from the seeds)",
                ShapeWarning,
                stacklevel=2,
            )
    return world


def build(config: RunConfig) -> Swarm:
    """A swarm ready for its first step."""
    world = load_world(config)
    return start_swarm(config, world, start_cells(config, world))


def start_cells(config: RunConfig, world: World) -> np.ndarray | None:
    """The start cells `config` asks for on `world` (None: random free cells)."""
    if config.start == "packed":
        return packed_start(world)
    if config.start is None or config.start == "scatter":
        return None
    return read_start_cells(Path(config.start), world)


def start_swarm(
    config: RunConfig,
    world: World,
    start: np.ndarray | None = None,
    plugin: Strategy | Program | None = None,
) -> Swarm:
    """A swarm on a given world (a painted one, say), run as `config` says, by `plugin` if
    given (a plug-in object made elsewhere: the learning environment's relay of a trainer's
    actions) instead of a new `config.strategy`."""
    strategy = plugin or strategies.create(
        config.strategy, order=config.order, senses=config.senses()
    )
    limits = Limits(config.max_speed, config.max_accel)
    params = Params(limits=limits, speed_variation=config.speed_variation)
    faults = Faults(config.faults, config.failure_rate)
    return Swarm(world, strategy, config.seeded().seed, params, start, faults)


def save(swarm: Swarm, path: Path, config: RunConfig) -> None:
    """Save a run to resume later (see `resume`): its description and every array, no code."""
    save_state(path, prefixed("config", config.values()) | prefixed("swarm", swarm.snapshot()))


def resume(path: Path, strategy: str | None = None) -> tuple[RunConfig, Swarm]:
    """A saved run's description and its swarm, ready for its next step.

    A state file holds no code: a run saved with a registered or installed strategy resumes by
    its name; one saved with ``file.py:Class`` or ``module:Class`` resumes only when the caller
    names that same `strategy` again.
    """
    saved = Snapshot(load_state(path))
    config = RunConfig.from_values(saved.part("config").plain(), f"{path}")
    if strategy is not None and strategy != config.strategy:
        raise InputError(
            f"{path}: was saved with the strategy {config.strategy!r}; a saved run resumes as "
            f"it was, so --strategy {strategy} cannot change it"
        )
    if strategies.is_code(config.strategy) and strategy is None:
        raise InputError(
            f"{path}: was saved with the strategy {config.strategy}, which is code; a state file "
            f"never loads code, so name it again to resume: --strategy {config.strategy}"
        )
    plugin = strategies.create(config.strategy, order=config.order, senses=config.senses())
    return config, Swarm.restored(saved.part("swarm"), plugin)


class Observer:
    """Anything that watches a run: it sees the swarm before the first step and after every
    step, and is closed once at the end (where files get written), or discarded if the run is
    abandoned. Subclass it and override what you need."""

    def capture(self, swarm: Swarm) -> None:
        """The swarm as it is now (before the first step, then after each)."""

    def close(self, swarm: Swarm) -> None:
        """The run ended: write what was gathered."""

    def discard(self) -> None:
        """The run was abandoned (an error, Ctrl+C): remove anything half-written."""


class Runner:
    """The one run loop: step a swarm and feed its observers, until the shape is formed,
    `max_steps` steps have run in total, or a local program has come to rest for good."""

    def __init__(
        self, swarm: Swarm, observers: Sequence[Observer] = (), max_steps: int | None = None
    ) -> None:
        self.swarm = swarm
        self.observers = tuple(observers)
        self.max_steps = RunConfig.max_steps if max_steps is None else max_steps
        for observer in self.observers:
            observer.capture(swarm)

    @property
    def out_of_steps(self) -> bool:
        return self.swarm.step_count >= self.max_steps

    @property
    def finished(self) -> bool:
        """Formed (or a local program gone quiet, or no robot left that can move) with no fault
        still to come, or out of steps."""
        swarm = self.swarm
        settled = swarm.complete or swarm.driver.quiet or swarm.stranded
        return (settled and not swarm.faults.ahead(swarm.step_count)) or self.out_of_steps

    def step(self) -> None:
        self.swarm.step()
        for observer in self.observers:
            observer.capture(self.swarm)

    def finish(self) -> Swarm:
        """Step to the end and close the observers (or discard them if stepping fails)."""
        try:
            while not self.finished:
                self.step()
        except BaseException:
            self.discard()
            raise
        self.close()
        return self.swarm

    def close(self) -> None:
        for observer in self.observers:
            observer.close(self.swarm)

    def discard(self) -> None:
        for observer in self.observers:
            observer.discard()


def run(swarm: Swarm, observers: Sequence[Observer] = (), max_steps: int | None = None) -> Swarm:
    """Run `swarm` to the end (formed, or `max_steps` in total); see `Runner`."""
    return Runner(swarm, observers, max_steps).finish()

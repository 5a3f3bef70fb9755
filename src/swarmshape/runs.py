"""One way to build and run a swarm: `build`, `Runner`, `save` and `resume`.

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
import tomllib
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from swarmshape import strategies
from swarmshape.config import RunConfig, plugin_options
from swarmshape.core.faults import Faults
from swarmshape.core.plugin import Plugin
from swarmshape.core.snapshot import Snapshot, SnapshotError, prefixed
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import World, build_world, packed_start
from swarmshape.errors import InputError
from swarmshape.io.bitmap import Picture, ShapeWarning
from swarmshape.io.checkpoint import load_state, save_state
from swarmshape.io.scenario import ImageOptions, load_scenario, read_start_cells


def registered_strategy(name: str) -> None:
    """Refuse, up front, a strategy that is not registered or installed: files of settings
    (scenarios, sweeps) are data and never name code."""
    if strategies.is_code(name):
        raise InputError(f"strategy {name!r} points at code; name a registered or installed one")
    strategies.get(name)


def one_per_world(names: Iterable[str]) -> list[str]:
    """One of the strategies `names` for each kind of world they have `load_world` build: one
    that grows from its seeds gets the shape's solid part, the others the shape as drawn."""
    return list({strategies.get(name).grows_from_seeds: name for name in names}.values())


def load_world(config: RunConfig, picture: Picture | None = None) -> World:
    """The scenario's groups, fitted to their robots and placed in the arena (`picture`: the
    image of an image's scenario, when it has been read already)."""
    path = config.shape_path
    image = ImageOptions(config.cells, config.threshold, config.invert)
    fit = config.agents if config.fit == "agents" else None
    scenario = load_scenario(path, image, fit, picture)
    specs = list(scenario.groups)
    if config.agents is not None:
        if len(specs) > 1:
            raise InputError("--agents applies to one shape; set agents per group in the scenario")
        specs[0] = dataclasses.replace(specs[0], agents=config.agents)
    plugin = strategies.get(config.strategy)
    grows = plugin.grows_from_seeds
    if grows:
        specs = [dataclasses.replace(spec, shape=spec.shape.seeded()) for spec in specs]
    packed = config.start == "packed"
    world = build_world(specs, config.arena, scenario.name, packed)
    cells = len(world.targets)
    if world.agents > 1.5 * cells and config.fit is None:
        warnings.warn(
            f"{world.agents:,} robots for a {cells:,}-cell shape: {world.agents - cells:,} "
            "will wait outside it; --fit agents sizes the shape to the robots",
            ShapeWarning,
            stacklevel=2,
        )
    if plugin.enters_from_outside:
        for group in world.groups:
            if sealed := len(group.shape.sealed(config.sense_radius)):
                cells = "1 cell" if sealed == 1 else f"{sealed:,} cells"
                warnings.warn(
                    f"shape {group.name!r} has {cells} in pieces that only pockets of the shape "
                    f"touch, beyond the sensing radius ({config.sense_radius:g}) of the rest: "
                    f"{config.strategy}'s robots step off the shape only toward an empty cell "
                    "they sense, so those fill only from robots that start in the pockets",
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


def files_read(config: RunConfig) -> dict[Path, str]:
    """Every file a run of `config` reads, and what it is to the run (for messages): no output
    may replace one, even with --force."""
    shape = config.shape_path
    if shape.suffix.lower() == ".toml":
        found = {shape: "its scenario"}
        found |= {image: "an image of its scenario" for image in scenario_images(shape)}
    else:
        found = {shape: "its image"}
    if isinstance(config.start, Path):
        found[config.start] = "its start cells"
    return found | strategy_file(config.strategy)


def strategy_file(strategy: str | None) -> dict[Path, str]:
    """The file of a strategy named as ``FILE.py:CLASS``, as `files_read` gives it."""
    module = (strategy or "").rpartition(":")[0]
    return {Path(module): "its strategy's code"} if module.endswith(".py") else {}


def scenario_images(path: Path) -> list[Path]:
    """The images a scenario file names (those it names as text; the scenario's reader checks
    the rest, and has already read this file's settings)."""
    try:
        groups = tomllib.loads(path.read_text(encoding="utf-8")).get("groups")
    except (OSError, ValueError, RecursionError):
        return []
    tables = groups if isinstance(groups, list) else []
    shapes = [table.get("shape") for table in tables if isinstance(table, dict)]
    return [path.parent / shape for shape in shapes if isinstance(shape, str)]


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
    plugin: Plugin | None = None,
) -> Swarm:
    """A swarm on a given world (a painted one, say), run as `config` says, by `plugin` if
    given (a plug-in object made elsewhere: the learning environment's relay of a trainer's
    actions) instead of a new `config.strategy`."""
    plugin = plugin or strategies.create(config.strategy, plugin_options(config))
    faults = Faults(config.faults, config.failure_rate)
    return Swarm(world, plugin, config.seeded().seed, config.params(), start, faults)


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
    plugin = strategies.create(config.strategy, plugin_options(config))
    try:
        return config, Swarm.restored(saved.part("swarm"), plugin)
    except SnapshotError as error:
        raise SnapshotError(f"{path}: {error}") from None


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
        self.stopped = False
        """Asked to end after the step under way (Ctrl+C), as if out of steps."""
        for observer in self.observers:
            observer.capture(swarm)

    @property
    def out_of_steps(self) -> bool:
        return self.swarm.step_count >= self.max_steps

    @property
    def finished(self) -> bool:
        """Formed (or a local program gone quiet, or no robot left that can move) with no fault
        still to come, out of steps, or stopped."""
        swarm = self.swarm
        settled = swarm.complete or swarm.driver.quiet or swarm.stranded
        done = settled and not swarm.faults.ahead(swarm.step_count)
        return done or self.out_of_steps or self.stopped

    def stop(self) -> None:
        """End the run after the step under way: its observers close on what it reached."""
        self.stopped = True

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

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
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from swarmshape import strategies
from swarmshape.core.motion import Limits
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import World, build_world
from swarmshape.errors import InputError
from swarmshape.io.bitmap import DEFAULT_CELLS, DEFAULT_THRESHOLD
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
    cells: int = DEFAULT_CELLS
    threshold: float = DEFAULT_THRESHOLD
    invert: bool = False
    arena: tuple[int, int] | None = None
    """Arena size in cells; None sizes it to the shape and the robots."""
    max_speed: float = Limits.max_speed
    max_accel: float = Limits.max_accel
    max_steps: int = 500_000
    start: Path | None = None
    """A CSV of start cells (columns x,y); None draws random free cells."""

    def __post_init__(self) -> None:
        if self.seed is not None and not 0 <= self.seed < 2**63:
            raise InputError(f"--seed must be a whole number from 0 to 2**63 - 1, got {self.seed}")
        if self.order not in ORDERS:
            raise InputError(f"unknown order {self.order!r}; choose one of {', '.join(ORDERS)}")
        if self.max_steps < 0:
            raise InputError(f"--max-steps must be 0 or more, got {self.max_steps}")
        Limits(self.max_speed, self.max_accel)  # checks them

    @property
    def shape_path(self) -> Path:
        return self.shape if self.shape is not None else bundled_shapes() / DEFAULT_SHAPE

    def seeded(self) -> RunConfig:
        """This description with a concrete seed (a fresh one if it had none)."""
        if self.seed is not None:
            return self
        return dataclasses.replace(self, seed=int(np.random.SeedSequence().generate_state(1)[0]))


def configure(shape: str | Path | None = None, **given: Any) -> RunConfig:
    """A complete description: `RunConfig`'s defaults, overridden by the settings of a scenario
    file, overridden by `given` (options left at None count as not given), with a seed."""
    path = None if shape is None else Path(shape)
    from_file = {} if path is None else scenario_settings(path)
    chosen = {key: value for key, value in given.items() if value is not None}
    unknown = sorted(set(chosen) - {f.name for f in dataclasses.fields(RunConfig)})
    if unknown:
        raise InputError(f"unknown run option {unknown[0]!r}")
    return RunConfig(shape=path, **{**from_file, **chosen}).seeded()


def bundled_shapes() -> Path:
    """The shipped shapes: inside an installed wheel, or the source checkout's shapes/."""
    installed = resources.files("swarmshape") / "shapes"
    if installed.is_dir():
        return Path(str(installed))
    return Path(__file__).resolve().parents[2] / "shapes"


def load_world(config: RunConfig) -> World:
    """The scenario's groups, fitted to their robots and placed in the arena."""
    path = config.shape_path
    scenario = load_scenario(path, ImageOptions(config.cells, config.threshold, config.invert))
    specs = list(scenario.groups)
    if config.agents is not None:
        if len(specs) > 1:
            raise InputError("--agents applies to one shape; set agents per group in the scenario")
        specs[0] = dataclasses.replace(specs[0], agents=config.agents)
    return build_world(specs, config.arena or scenario.arena, scenario.name)


def build(config: RunConfig) -> Swarm:
    """A swarm ready for its first step."""
    world = load_world(config)
    start = None if config.start is None else read_start_cells(config.start, world)
    return start_swarm(config, world, start)


def start_swarm(config: RunConfig, world: World, start: np.ndarray | None = None) -> Swarm:
    """A swarm on a given world (a painted one, say), run as `config` says."""
    strategy = strategies.create(config.strategy, order=config.order)
    params = Params(limits=Limits(config.max_speed, config.max_accel))
    return Swarm(world, strategy, config.seeded().seed, params, start)


def save(swarm: Swarm, path: Path, config: RunConfig) -> None:
    """Save a run to resume later (see `resume`)."""
    save_state(swarm, path, dataclasses.asdict(config))


def resume(path: Path) -> tuple[RunConfig, Swarm]:
    """A saved run's description and its swarm, ready for its next step."""
    saved = load_state(path)
    return RunConfig(**saved.config), saved.swarm


class Observer(Protocol):
    """Anything that watches a run: it sees the swarm before the first step and after every
    step, and is closed once at the end (where files get written)."""

    def capture(self, swarm: Swarm) -> None: ...

    def close(self, swarm: Swarm) -> None: ...


class Runner:
    """The one run loop: step a swarm and feed its observers, until the shape is formed or
    `max_steps` steps have run in total."""

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
        return self.swarm.complete or self.out_of_steps

    def step(self) -> None:
        self.swarm.step()
        for observer in self.observers:
            observer.capture(self.swarm)

    def finish(self) -> Swarm:
        """Step to the end and close the observers."""
        while not self.finished:
            self.step()
        self.close()
        return self.swarm

    def close(self) -> None:
        for observer in self.observers:
            observer.close(self.swarm)


def run(swarm: Swarm, observers: Sequence[Observer] = (), max_steps: int | None = None) -> Swarm:
    """Run `swarm` to the end (formed, or `max_steps` in total); see `Runner`."""
    return Runner(swarm, observers, max_steps).finish()

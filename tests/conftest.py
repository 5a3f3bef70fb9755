"""Shared fixtures. Tests never need a screen: SDL uses its dummy drivers."""

from __future__ import annotations

import importlib.util
import os
import sys

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from hypothesis import settings

from swarmshape.core.shape import Shape
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.strategies import create

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

# The suite's own pace: enough examples of each property to catch a rule broken anywhere common,
# in the few minutes a change's test run may take. `--slow` runs twenty times as many, and the
# tests marked slow (large swarms, long regressions): what a night run is for. `scripts/test`
# (and so CI) checks the same examples every run ("ci"), so a change is judged on what it
# changed and a red build always reproduces; plain `pytest` draws new ones and so keeps
# exploring.
settings.register_profile("quick", max_examples=50)
settings.register_profile("ci", parent=settings.get_profile("quick"), derandomize=True,
                          print_blob=True)  # fmt: skip
settings.register_profile("slow", max_examples=1000)
settings.load_profile(os.environ.get("SWARMSHAPE_HYPOTHESIS_PROFILE", "quick"))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--slow", action="store_true", help="the slow tests too, and many more examples"
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: runs only with --slow (large swarms, long runs)")
    if config.getoption("--slow"):
        settings.load_profile("slow")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Leave the tests marked slow out of a run without `--slow`, and say so."""
    if config.getoption("--slow"):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]


def slow_for(slow: str, param: str) -> object:
    """`param` of a parametrised test, marked slow when it is `slow` (a plug-in whose runs of
    the test take a minute where the others take seconds)."""
    return pytest.param(param, marks=pytest.mark.slow) if param == slow else param


@pytest.fixture
def shapes() -> Path:
    return SHAPES


def grid_from(text: str) -> np.ndarray:
    """A grid from rows of '#' (ink) and '.' (empty)."""
    return np.array([[c == "#" for c in row] for row in text.split()], dtype=bool)


def world_of(shape: np.ndarray | Shape, agents: int | None = None) -> World:
    shape = shape if isinstance(shape, Shape) else Shape(shape)
    return build_world([GroupSpec("test", shape, (200, 60, 60), agents)])


def make_swarm(
    shape: np.ndarray | Shape,
    *,
    agents: int | None = None,
    seed: int = 0,
    strategy: str = "paper",
) -> Swarm:
    """A swarm forming `shape` (moved beside its seeds for a program that grows from them,
    as `runs.load_world` does)."""
    program = create(strategy)
    shape = shape if isinstance(shape, Shape) else Shape(shape)
    if getattr(program, "grows_from_seeds", False):
        shape = shape.seeded()
    return Swarm(world_of(shape, agents), program, seed)


def script(name: str) -> ModuleType:
    """A script of scripts/ as a module (they are not a package)."""
    spec = importlib.util.spec_from_file_location(name, SHAPES.parent / "scripts" / f"{name}.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # a dataclass looks its module up there
    spec.loader.exec_module(module)
    return module

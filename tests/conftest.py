"""Shared fixtures. Tests never need a screen: SDL uses its dummy drivers."""

from __future__ import annotations

import os

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

from swarmshape.core.shape import Shape
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.strategies import create

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

# CI checks the same examples every run, so a red build always reproduces; runs elsewhere
# draw new ones and so keep exploring.
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("slow", max_examples=1000)
if os.environ.get("CI"):
    settings.load_profile("ci")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--slow", action="store_true", help="many more hypothesis examples")


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("--slow"):
        settings.load_profile("slow")


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

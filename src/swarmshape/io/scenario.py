"""What to run: an image or a TOML scenario, read into one frozen `Scenario`.

A TOML scenario names its shapes relative to its own folder::

    strategy = "paper"        # any run setting, optional (swarmshape.config.RunConfig)
    seed = 7
    arena = [40, 24]          # width, height in cells; automatic when left out

    [options]                 # the strategy's own options
    order = "outward"

    [[groups]]
    name = "blue"
    shape = "small-square.png"
    agents = 36               # default: one per cell of the shape
    colour = "#3a6fd8"
    pose = { x = 6, y = 5, rotation = 0 }   # seed frame origin; rotation in quarter turns

An image is a scenario with one group named after the file.
"""

from __future__ import annotations

import csv
import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import ImageColor

from swarmshape.core.shape import Pose, Shape, ShapeError
from swarmshape.core.world import GroupSpec, World
from swarmshape.errors import InputError
from swarmshape.io.bitmap import (
    DEFAULT_THRESHOLD,
    Picture,
    grid_for,
    grid_of,
    load_grid,
    read_picture,
)
from swarmshape.io.files import read_toml, readable_file

PALETTE = ("#3a6fd8", "#d9483b", "#e69b23", "#8a4fc9", "#2fa8a0", "#c94f8a")
"""Group colours in order; none of them green (seeds) or grey (targets)."""

GROUP_SETTINGS = ("agents", "cells", "threshold", "invert")
"""Run settings that a group may set for itself."""
GROUP_KEYS = {"name", "shape", "colour", "pose", *GROUP_SETTINGS}
POSE_KEYS = {"x", "y", "rotation"}


class ScenarioError(InputError):
    """A scenario file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class ImageOptions:
    """How images become grids (the loader's knobs)."""

    cells: int | None = None
    threshold: float = DEFAULT_THRESHOLD
    invert: bool = False


@dataclass(frozen=True)
class Scenario:
    """The groups to form; the file's run settings come from `scenario_settings`."""

    name: str
    groups: tuple[GroupSpec, ...]


def load_scenario(
    path: str | Path,
    image: ImageOptions | None = None,
    fit: int | None = None,
    picture: Picture | None = None,
) -> Scenario:
    """Read an image (one group) or a ``.toml`` scenario. With `fit`, an image is sized to
    have as many cells as possible up to that many (to fill that many robots). `picture` is
    the image at `path` when it has been read already (a preview shows it too)."""
    path = Path(path)
    image = image or ImageOptions()
    if path.suffix.lower() != ".toml":
        if picture is None:
            picture = read_picture(path, threshold=image.threshold, invert=image.invert)
        grid = grid_of(picture, image.cells) if fit is None else grid_for(picture, fit)
        return Scenario(path.name, (GroupSpec(path.stem, Shape(grid), parse_colour(PALETTE[0])),))
    if fit is not None:
        raise ScenarioError(f"{path}: --fit agents sizes one image; set cells per group instead")
    data, where = _read_toml(path)
    groups = data.get("groups")
    if not isinstance(groups, list) or not groups:
        raise ScenarioError(f"{path}: needs at least one [[groups]] table with a shape")
    specs = tuple(_group(where, index, table, image) for index, table in enumerate(groups))
    names = [spec.name for spec in specs]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise ScenarioError(f"{path}: two groups are named {twice[0]!r}; give each its own name")
    name = where.typed(data.get("name", path.name), str, "name")
    return Scenario(name, specs)


def scenario_settings(path: str | Path) -> dict[str, Any]:
    """The run settings a scenario file sets (none for an image), as plain values, without
    loading its shapes: every top-level key but ``name`` and ``groups``, its ``[options]``
    table included. The run checks them (`swarmshape.config.configure`)."""
    path = Path(path)
    if path.suffix.lower() != ".toml":
        return {}
    data, _ = _read_toml(path)
    if "shape" in data:  # a run setting elsewhere; here the file is the shape
        raise ScenarioError(
            f'{path}: a scenario names its images in [[groups]] (shape = "..." in each), '
            "not as a top-level shape"
        )
    return {key: value for key, value in data.items() if key not in ("name", "groups")}


def group_settings(path: str | Path) -> list[dict[str, Any]]:
    """The run settings (`GROUP_SETTINGS`) that each group of a scenario file sets for itself,
    as plain values, for the run to check as it checks the file's own; none for an image, or
    for groups that are not a list of tables (loading the scenario says what is wrong)."""
    path = Path(path)
    if path.suffix.lower() != ".toml":
        return []
    groups = _read_toml(path)[0].get("groups")
    if not isinstance(groups, list) or not all(isinstance(group, dict) for group in groups):
        return []
    return [{key: group[key] for key in GROUP_SETTINGS if key in group} for group in groups]


def _read_toml(path: Path) -> tuple[dict[str, Any], _Where]:
    return read_toml(path, "a .toml scenario", ScenarioError), _Where(path)


def _group(where: _Where, index: int, table: Any, image: ImageOptions) -> GroupSpec:
    label = f"groups[{index}]"
    if not isinstance(table, dict):
        raise ScenarioError(f"{where.path}: {label} must be a table")
    where.known(table, GROUP_KEYS, label)
    if "shape" not in table:
        raise ScenarioError(f"{where.path}: {label} needs a shape (an image path)")
    shape_path = where.path.parent / where.typed(table["shape"], str, f"{label}.shape")
    cells = table.get("cells", image.cells)
    grid = load_grid(
        shape_path,
        cells=None if cells is None else where.typed(cells, int, f"{label}.cells"),
        threshold=float(
            where.typed(table.get("threshold", image.threshold), (int, float), f"{label}.threshold")
        ),
        invert=where.typed(table.get("invert", image.invert), bool, f"{label}.invert"),
    )
    agents = table.get("agents")
    if agents is not None:
        agents = where.typed(agents, int, f"{label}.agents")
    colour = where.typed(table.get("colour", PALETTE[index % len(PALETTE)]), str, f"{label}.colour")
    try:
        rgb = parse_colour(colour)
    except ValueError:
        raise ScenarioError(f"{where.path}: {label}.colour {colour!r} is not a colour") from None
    pose = None
    if "pose" in table:
        pose_table = table["pose"]
        if not isinstance(pose_table, dict):
            raise ScenarioError(f"{where.path}: {label}.pose must be a table like {{x = 0, y = 0}}")
        where.known(pose_table, POSE_KEYS, f"{label}.pose")
        values = {k: where.typed(v, int, f"{label}.pose.{k}") for k, v in pose_table.items()}
        try:
            pose = Pose(**values)
        except ShapeError as error:
            raise ScenarioError(f"{where.path}: {label}.pose: {error}") from None
    name = where.typed(table.get("name", f"group {index + 1}"), str, f"{label}.name")
    return GroupSpec(name, Shape(grid), rgb, agents, pose)


def parse_colour(colour: str) -> tuple[int, int, int]:
    """Red, green and blue, 0 to 255, of a colour name or specifier; ValueError for anything
    else, including what Pillow reads beyond that range (``rgb(999,0,0)``, ``hsl(999,...)``)."""
    red, green, blue = ImageColor.getrgb(colour)[:3]
    if not all(0 <= channel <= 255 for channel in (red, green, blue)):
        raise ValueError(f"{colour!r} is beyond 0 to 255")
    return red, green, blue


@dataclass(frozen=True)
class _Where:
    """Checks that name the file and key in their messages."""

    path: Path

    def known(self, table: dict, allowed: set[str], label: str) -> None:
        unknown = sorted(set(table) - allowed)
        if unknown:
            raise ScenarioError(
                f"{self.path}: unknown key {unknown[0]!r} in {label}; "
                f"expected one of {', '.join(sorted(allowed))}"
            )

    def typed(self, value: Any, kind: type | tuple[type, ...], key: str) -> Any:
        is_bool = isinstance(value, bool)
        wants_bool = kind is bool or (isinstance(kind, tuple) and bool in kind)
        if not isinstance(value, kind) or (is_bool and not wants_bool):
            names = " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
            raise ScenarioError(f"{self.path}: {key} must be {names}, got {value!r}")
        return value


def read_start_cells(path: Path, world: World) -> np.ndarray:
    """Start cells ``(agents, 2)`` from a CSV with columns ``x,y`` (one row per agent, groups
    in scenario order): free arena cells, none on a shape or a seed, no two alike."""
    path = readable_file(Path(path), "a CSV of start cells")
    try:  # rows past one more than the robots are counted, not kept: a huge file is refused
        with path.open(newline="", encoding="utf-8-sig") as handle:  # a BOM is no column name
            reader = csv.DictReader(handle)
            reader.fieldnames = [name.strip() for name in reader.fieldnames or []]  # "x, y"
            rows = list(itertools.islice(reader, world.agents + 1))
            extra = sum(1 for _ in reader)
    except OSError as error:
        raise InputError(f"{path}: cannot read start positions ({error.strerror})") from None
    except (UnicodeDecodeError, csv.Error) as error:
        raise InputError(f"{path}: not a CSV of start positions ({error})") from None
    try:
        numbers = [(int(row["x"]), int(row["y"])) for row in rows]
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{path}: needs integer columns x,y (cells), one row per agent") from None
    if len(numbers) + extra != world.agents:
        robots = f"{world.agents} robot{'' if world.agents == 1 else 's'}"
        raise InputError(f"{path}: {len(numbers) + extra} start positions for {robots}")
    cells = np.array([(-1, -1) if max(abs(x), abs(y)) > 2**62 else (x, y) for x, y in numbers])
    allowed = world.start_mask()
    inside = (cells >= 0).all(axis=1) & (cells < np.array(world.size)).all(axis=1)
    ok = np.zeros(len(cells), dtype=bool)
    ok[inside] = allowed[cells[inside, 0], cells[inside, 1]]
    bad = np.flatnonzero(~ok)
    if len(bad):
        x, y = numbers[bad[0]]
        raise InputError(
            f"{path}: row {bad[0] + 2} ({x},{y}) is not a free start cell "
            "(outside the arena, or on or next to a shape or a seed)"
        )
    if len(np.unique(cells, axis=0)) < len(cells):
        raise InputError(f"{path}: two robots start on the same cell")
    return cells

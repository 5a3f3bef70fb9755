"""What a robot works out from the bitmap it holds: how deep each cell lies in its shape. Every
robot of a group holds the same bitmap and seed frame, so it can work this out alone; it is
computed once per bitmap and looked up after that.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import ndimage

from swarmshape.core.perception import Blueprint, box_lookup
from swarmshape.core.shape import SEED_CELLS

MARGIN = 2
"""Cells round the shape's box: a robot farther out is looked up on the box's edge."""


def depth(blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Each frame cell's taxicab distance to the nearest cell outside its group's shape, 0
    outside it. The seeds count as inside (no robot comes in past them), and so do pockets
    the shape encloses, which no robot comes in from: a cell is deep when it lies far from
    where robots come in."""
    return box_lookup(_depths(blueprint), groups, frame)


def enclosed(blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Whether each frame cell lies outside its group's shape in a pocket the shape (with its
    seeds) encloses: a robot there can come in only through the pocket's own rim."""
    return (depth(blueprint, groups, frame) > 0) & ~blueprint.contains(groups, frame)


@functools.lru_cache(maxsize=4)
def _depths(blueprint: Blueprint) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Per group, the depth of each cell as a box for `box_lookup` (the low corner less one,
    and a grid whose border holds what lies beyond)."""
    depths = []
    for shape in blueprint.cells:
        cells = np.concatenate([shape, SEED_CELLS])
        low = cells.min(axis=0) - MARGIN - 1
        size = cells.max(axis=0) + MARGIN + 2 - low
        grid = np.zeros(size, dtype=bool)
        grid[cells[:, 0] - low[0], cells[:, 1] - low[1]] = True
        inside = ndimage.binary_fill_holes(grid)
        depths.append((low, ndimage.distance_transform_cdt(inside, "taxicab")))
    return tuple(depths)


@functools.lru_cache(maxsize=4)
def rim(blueprint: Blueprint) -> int:
    """Cells a walk once round every group's shape passes: its cells beside the outside."""
    return sum(int((depths == 1).sum()) for _, depths in _depths(blueprint))

"""What a robot works out from the bitmap it holds: how deep each cell lies in its shape. Every
robot of a group holds the same bitmap and seed frame, so it can work this out alone; it is
computed once per bitmap and looked up after that.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy

from swarmshape.core.perception import Blueprint, Boxes
from swarmshape.core.shape import SEED_CELLS, Shape

MARGIN = 2
"""Cells round the shape's box: a robot farther out is looked up on the box's edge."""


def depth(blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """How deep each frame cell lies in its group's shape, 0 outside it: for a shape cell, the
    fewest moves through shape cells to one beside the outside, plus one; for a pocket the
    shape encloses, or a seed, its taxicab distance to the outside. The seeds count as inside
    (no robot comes in past them), and so do the pockets, which no robot comes in from: a cell
    is deep when it lies far from where robots come in. Counted through the shape, every shape
    cell deeper than 1 has a shape cell a step shallower beside it, so a hole carried outward
    never sticks beside a pocket (the horse's one-cell slot held one for good)."""
    return _depths(blueprint).at(groups, frame)


class Around:
    """What each robot's bitmap says of the cells round its frame cell, within `reach` cells
    either way: whether they are in its shape, their `depth`, and so whether they are
    `enclosed`, and whether they lie in a `sealed` piece, looked up by offsets from the frame
    cell ``(n, ..., 2)``. Worked out once a step: a program that looks up the same cells a
    dozen times a step (`mean-shift`) spent a sixth of its step on the lookups.

    The `last` of a step before (the same robots) lends its squares, which it gives up: only
    the rows of robots whose group or frame cell has changed since are worked out again.
    Worked out for every robot, they cost a 10,000-robot `mean-shift` step 1.5 ms, when most
    of its robots stand still."""

    inside: np.ndarray
    """Per robot ``(n, side, side)``, its frame cell in the middle: in its shape or not."""
    depths: np.ndarray
    """The same square's `depth`s, for a compiled pass that looks up many (`_at`)."""

    def __init__(
        self,
        blueprint: Blueprint,
        groups: np.ndarray,
        frame: np.ndarray,
        reach: int,
        last: Around | None = None,
    ) -> None:
        self.reach = reach
        self._of = (blueprint, groups.copy(), frame.copy())
        if (
            last is None
            or last.reach != reach
            or last._of[0] is not blueprint
            or len(last._of[1]) != len(groups)
        ):
            self.inside, self.depths, self._sealed = _squares(blueprint, groups, frame, reach)
            return
        _, last_groups, last_frame = last._of
        rows = np.flatnonzero(
            (last_groups != groups) | (last_frame[:, 0] != frame[:, 0])
            | (last_frame[:, 1] != frame[:, 1])
        )  # fmt: skip
        inside, depths, sealed = _squares(blueprint, groups[rows], frame[rows], reach)
        self.inside, self.depths, self._sealed = last.inside, last.depths, last._sealed
        self.inside[rows], self.depths[rows] = inside, depths
        if self._sealed is not None:
            self._sealed[rows] = sealed

    def contains(self, offsets: np.ndarray) -> np.ndarray:
        return self._at(self.inside, offsets)

    def depth(self, offsets: np.ndarray, robots: np.ndarray | None = None) -> np.ndarray:
        """Per robot (of `robots` only, if given, their offsets ``(k, ..., 2)``)."""
        return self._at(self.depths, offsets, robots)

    def sealed(self, offsets: np.ndarray) -> np.ndarray:
        """Whether each cell lies in a piece of the shape that touches no cell of the outside,
        only pockets that other pieces enclose (`Shape.sealed`)."""
        if self._sealed is None:  # no group's shape has such a piece
            return np.zeros_like(self._at(self.inside, offsets))
        return self._at(self._sealed, offsets)

    @property
    def any_sealed(self) -> bool:
        """Whether some group's shape has a piece that only its pockets touch."""
        return self._sealed is not None

    def enclosed(self, offsets: np.ndarray) -> np.ndarray:
        """Whether each cell lies outside the shape in a pocket the shape (with its seeds)
        encloses: a robot there can come in only through the pocket's own rim."""
        return (self.depth(offsets) > 0) & ~self.contains(offsets)

    def _at(
        self, square: np.ndarray, offsets: np.ndarray, robots: np.ndarray | None = None
    ) -> np.ndarray:
        """`square`'s values at `offsets`: per robot ``(n, ..., 2)`` (or per robot of
        `robots`), or the same for every robot ``(1, k, 2)``. A program looks up two dozen
        sets of cells a step, so each is one gather from the squares laid end to end."""
        n, side = square.shape[:2]
        if np.abs(offsets).max(initial=0) > self.reach:
            raise ValueError(f"an offset lies beyond the {self.reach} cells worked out")
        index = (offsets[..., 0] + self.reach) * side + (offsets[..., 1] + self.reach)
        if robots is None and index.ndim == 2 and len(index) == 1:
            return square.reshape(n, -1)[:, index[0]]
        rows = np.arange(n) if robots is None else robots
        rows = rows.reshape(-1, *[1] * (index.ndim - 1)) * (side * side)
        return square.reshape(-1)[rows + index]


def _squares(
    blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray, reach: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """`Around`'s squares round each frame cell: in the shape, depths, in a sealed piece (None
    when no group's shape has one)."""
    sealed = _sealed(blueprint)
    return (
        blueprint.contains_around(groups, frame, reach),
        _depths(blueprint).around(groups, frame, reach),
        None if sealed is None else sealed.around(groups, frame, reach),
    )


@functools.lru_cache(maxsize=4)
def _depths(blueprint: Blueprint) -> Boxes:
    """Per group, the depth of each cell of a box round its shape (whose border holds what
    lies beyond)."""
    depths = []
    for shape in blueprint.cells:
        cells = np.concatenate([shape, SEED_CELLS])
        low = cells.min(axis=0) - MARGIN - 1
        size = cells.max(axis=0) + MARGIN + 2 - low
        body = np.zeros(size, dtype=bool)
        body[shape[:, 0] - low[0], shape[:, 1] - low[1]] = True
        grid = body.copy()
        grid[SEED_CELLS[:, 0] - low[0], SEED_CELLS[:, 1] - low[1]] = True
        depths.append((low, _through(body, scipy.ndimage.binary_fill_holes(grid))))
    return Boxes(depths)


@functools.lru_cache(maxsize=4)
def _sealed(blueprint: Blueprint) -> Boxes | None:
    """Per group, which cells of a box round its shape lie in a piece that only its pockets
    touch (`Shape.sealed`); None when no group's shape has one."""
    boxes = []
    for shape in blueprint.cells:
        low = shape.min(axis=0) - 1 if len(shape) else np.zeros(2, dtype=np.int64)
        grid = np.zeros(shape.max(axis=0) + 2 - low if len(shape) else (1, 1), dtype=bool)
        if len(shape):
            sealed = Shape.from_cells(shape).sealed()
            grid[sealed[:, 0] - low[0], sealed[:, 1] - low[1]] = True
        boxes.append((low, grid))
    return Boxes(boxes) if any(grid.any() for _, grid in boxes) else None


def _through(shape: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """The depth of each cell of a box (see `depth`): `shape` its shape cells, `inside` those
    and the seeds and pockets. A shape cell walled off from the outside by pockets keeps its
    taxicab depth."""
    depths = scipy.ndimage.distance_transform_cdt(inside, "taxicab")
    front = shape & (depths == 1)
    reached, level = front.copy(), 1
    four = scipy.ndimage.generate_binary_structure(2, 1)
    while front.any():
        depths[front] = level
        front = scipy.ndimage.binary_dilation(front, four) & shape & ~reached
        reached |= front
        level += 1
    return depths


@functools.lru_cache(maxsize=4)
def rim(blueprint: Blueprint) -> int:
    """Cells a walk once round every group's shape passes: its cells beside the outside."""
    return sum(int((depths == 1).sum()) for _, depths in _depths(blueprint).boxes)


def tour(
    blueprint: Blueprint, groups: np.ndarray, index: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per robot, the frame cell at place `index` of its group's tour, and the tour's length:
    the shape's cells beside the outside in turn round their middle, so that a walk from one to
    the next passes every piece of the shape (a robot beside a full piece finds the others)."""
    cells = np.zeros((len(groups), 2), dtype=np.int64)
    length = np.zeros(len(groups), dtype=np.int64)
    for group, walk in enumerate(_tours(blueprint)):
        if not len(walk):  # a group left with no cells
            continue
        mine = np.flatnonzero(groups == group)
        cells[mine] = walk[index[mine] % len(walk)]
        length[mine] = len(walk)
    return cells, length


def nearest_on_tour(blueprint: Blueprint, groups: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Per robot, the place on its group's tour (see `tour`) of the tour cell nearest its frame
    cell ``(n, 2)``."""
    index = np.zeros(len(groups), dtype=np.int64)
    for group, walk in enumerate(_tours(blueprint)):
        if not len(walk):
            continue
        mine = np.flatnonzero(groups == group)
        away = walk[None] - frame[mine, None]
        index[mine] = np.argmin(np.hypot(away[..., 0], away[..., 1]), axis=1)
    return index


@functools.lru_cache(maxsize=4)
def _tours(blueprint: Blueprint) -> tuple[np.ndarray, ...]:
    """Per group, its tour (see `tour`): the rim cells by their angle round the rim's mean
    cell, nearer ones first at one angle."""
    tours = []
    for shape, (low, depths) in zip(blueprint.cells, _depths(blueprint).boxes, strict=True):
        rim = shape[depths[shape[:, 0] - low[0], shape[:, 1] - low[1]] == 1]
        away = rim - rim.mean(axis=0) if len(rim) else rim
        tours.append(rim[np.lexsort((np.hypot(*away.T), np.arctan2(away[:, 1], away[:, 0])))])
    return tuple(tours)

"""Boolean grids shared by shapes and images: cropping to the ink, shrinking by area, and
how much of a picture a grid keeps (`likeness`).

A grid here is indexed ``[row, col]`` with row 0 at the top, as an image is seen. Images are
read elsewhere (`swarmshape.io.bitmap`); these operations are numpy and scipy only, so the core
can shrink a shape to fewer robots while it runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy

KEPT = 0.5
"""Least IoU between a picture and its shape scaled back up to it for the shape to keep the
picture: at a half they have as much in common as they differ, the rule that makes a cell ink."""

PART = 4
"""Cells of area a piece of ink or a hole must have to count as a part of the picture: a
square of 2x2 cells keeps a whole cell wherever the grid falls on it, a smaller part may vanish
by chance (a thin stroke of that area is a part: only a finer grid keeps it)."""


def crop(grid: np.ndarray) -> np.ndarray:
    """Cut the empty rows and columns around the ink (an empty grid stays as it is)."""
    return bounding_box(grid) if grid.any() else grid


def bounding_box(image: np.ndarray) -> np.ndarray:
    """The smallest block of rows and columns holding every non-zero pixel (a view; there
    must be one)."""
    rows, cols = np.flatnonzero(image.any(axis=1)), np.flatnonzero(image.any(axis=0))
    return image[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]


def resample(fraction: np.ndarray, long_side: int) -> np.ndarray:
    """Resize a 0..1 ink image so its long side is `long_side` cells; ink where >= half.

    Shrinking, each output cell averages the pixels whose centres fall in its box (`resized`).
    Growing, each cell takes the pixel under its centre, so a small icon becomes the same
    picture in bigger blocks.
    """
    size = sized(fraction.shape, long_side)
    if long_side >= max(fraction.shape):
        return stretched(fraction, size) >= 0.5
    return resized(fraction, size) >= 0.5


def sized(shape: tuple[int, ...], long_side: int) -> tuple[int, int]:
    """Rows and columns of an image of `shape` resized to `long_side` across its long side."""
    height, width = shape
    factor = long_side / max(height, width)
    return max(1, round(height * factor)), max(1, round(width * factor))


def resized(fraction: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A 0..1 image resized to `shape` (float32): area-averaged along each axis it shrinks
    (each output pixel the mean of the pixels whose centres fall in its box, columns first,
    in float32 between the passes: the filter Pillow calls BOX, so shapes shrink the same way
    images are loaded), each pixel repeated along an axis it grows."""
    result = fraction.astype(np.float32)
    for axis in (1, 0):
        if shape[axis] < result.shape[axis]:
            result = _box_average(result, shape[axis], axis=axis)
    return result if result.shape == shape else stretched(result, shape)


def stretched(image: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """`image` resized to `shape` by taking, for each output pixel, the pixel under its
    centre."""
    height, width = image.shape
    rows = np.minimum(((np.arange(shape[0]) + 0.5) * height / shape[0]).astype(int), height - 1)
    cols = np.minimum(((np.arange(shape[1]) + 0.5) * width / shape[1]).astype(int), width - 1)
    return image[np.ix_(rows, cols)]


def _box_average(image: np.ndarray, out: int, axis: int) -> np.ndarray:
    """Average along `axis` down to `out` samples: each sample the mean of the pixels whose
    centres fall in its box, summed in double. The boxes are worked out per sample and summed
    segment by segment, so the cost and the memory are those of the image and the result, not
    of samples times pixels per box (a 1 x 25,000,000 picture took 2 GB that way)."""
    moved = np.moveaxis(image, axis, -1)
    size = moved.shape[-1]
    scale = size / out
    support = 0.5 * max(scale, 1.0)
    centre = (np.arange(out) + 0.5) * scale
    first = np.maximum((centre - support + 0.5).astype(np.int64), 0)
    last = np.minimum((centre + support + 0.5).astype(np.int64), size)

    def inside(tap: np.ndarray) -> np.ndarray:  # a pixel's centre within its sample's box
        position = (tap + first - centre + 0.5) * (1.0 / max(scale, 1.0))
        return (position > -0.5) & (position <= 0.5)

    # only a pixel at either end of a box can have its centre on the box's edge; boxes may
    # leave a pixel out, so each is summed from its start to its own stop (reduceat sums from
    # one index to the next: the even segments are the boxes, the odd ones are dropped)
    start = first + ~inside(np.zeros(out, dtype=np.int64))
    stop = last - ~inside(last - first - 1)
    bounds = np.column_stack([start, stop]).reshape(-1)
    sums = np.add.reduceat(moved, bounds[bounds < size], axis=-1, dtype=np.float64)[..., ::2]
    return np.moveaxis((sums / (stop - start)).astype(np.float32), -1, axis)


@dataclass(frozen=True)
class Likeness:
    """How much of its picture a grid keeps. The grid is scaled back up to a reference of the
    picture (its ink area-averaged to a few pixels a cell): `iou` is the ink they share over
    the ink of either, the picture's as fractions. The picture's parts are its pieces of ink
    (8-connected) and its holes (4-connected) no smaller than a cell of the coarsest grid
    asked about, of as many cells (see `likeness`); each must be kept: overlapped by the grid,
    mostly by one piece, and by a piece of its own (see `_unkept`)."""

    iou: float
    parts: int
    holes: int
    lost_parts: int
    lost_holes: int

    @property
    def kept(self) -> bool:
        return self.iou >= KEPT and not self.lost_parts and not self.lost_holes

    def losses(self) -> str:
        """What the grid loses, in words ("" when nothing)."""
        lost = [
            f"{count} of the picture's {total} {noun if total > 1 else noun[:-1]}"
            for count, total, noun in [
                (self.lost_parts, self.parts, "parts"),
                (self.lost_holes, self.holes, "holes"),
            ]
            if count
        ]
        if self.iou < KEPT:
            lost.append(f"much of its area (IoU {self.iou:.2f})")
        return ", ".join(lost[:-1]) + " and " * (len(lost) > 1) + lost[-1] if lost else ""


def likeness(reference: np.ndarray, grid: np.ndarray, coarsest: int) -> Likeness:
    """How much of a picture, given as a `reference` of ink fractions, `grid` keeps. A part
    counts when it has at least one cell of a grid of `coarsest` x `coarsest` cells spread
    over the picture's box, and `PART` of the grid's cells or of that grid's, whichever are
    smaller: finer detail (the grain of a photo, which grows without end as the grid does) is
    not asked for, and a grid coarser than that one is asked what it would keep. Counted by
    the grid's own cells, a ten-letter word logo 32 cells across, 4 rows of cells 26 pixels
    wide, was asked to keep only its seven largest letters and none of its counters, and was
    given as 32 x 4 cells of blots with no warning."""
    scaled = stretched(grid, reference.shape)
    shared = float(np.sum(reference, where=scaled, dtype=np.float64))
    either = float(np.sum(reference, where=~scaled, dtype=np.float64)) + float(scaled.sum())
    cell = reference.shape[0] / grid.shape[0] * reference.shape[1] / grid.shape[1]
    coarse = reference.size / coarsest**2
    least = max(PART * min(cell, coarse), coarse)
    ink = reference >= 0.5
    eight = np.ones((3, 3), dtype=bool)
    parts, lost_parts = _unkept(_parts(ink, eight), _parts(grid, eight, scaled.shape), least)
    holes, lost_holes = _unkept(
        _parts(~ink, None, hole=True), _parts(~grid, None, scaled.shape, hole=True), least
    )
    return Likeness(shared / either if either else 1.0, parts, holes, lost_parts, lost_holes)


def _parts(
    image: np.ndarray,
    structure: np.ndarray | None,
    shape: tuple[int, int] | None = None,
    hole: bool = False,
) -> np.ndarray:
    """Labels of `image`'s connected parts (with `hole`, only those off the border), scaled
    to `shape`."""
    labels, _ = scipy.ndimage.label(image, structure)
    if hole:
        border = np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])
        labels[np.isin(labels, border)] = 0
    return labels if shape is None else stretched(labels, shape)


def _unkept(picture: np.ndarray, grid: np.ndarray, least: float) -> tuple[int, int]:
    """Of the picture's parts of at least `least` pixels: how many, and how many are lost
    (no piece of the grid overlaps it), broken (no one piece of the grid holds more than `KEPT`
    of what the grid keeps of it: a crumb cut off a large part is not a loss, a stroke cut in
    two is) or merged (a piece of the grid overlaps it and another by `least` or more, and
    the other more). Each part counts once, however many ways it is lost: counted per piece of
    the grid, a line drawing at 60 cells lost "3 of the picture's 2 parts"."""
    area = np.bincount(picture.ravel())
    counted = area >= least
    counted[0] = False
    both = counted[picture] & (grid > 0)
    span = int(grid.max()) + 1
    keys = picture[both].astype(np.int64) * span + grid[both]  # one per overlapping pixel
    if len(area) * span <= len(keys):  # counted in one pass when the table is no larger
        overlap = np.bincount(keys, minlength=len(area) * span)
        pairs = np.flatnonzero(overlap)
        overlap = overlap[pairs]
    else:
        pairs, overlap = np.unique(keys, return_counts=True)
    part, piece = pairs // span, pairs % span
    kept = np.bincount(part, overlap, minlength=len(area))
    largest = np.zeros(len(area))
    np.maximum.at(largest, part, overlap)
    broken = largest <= KEPT * kept
    # of the parts a piece overlaps by `least` or more, all but the one it overlaps most
    large = np.flatnonzero(overlap >= least)
    large = large[np.lexsort((-overlap[large], piece[large]))]
    merged = np.zeros(len(area), dtype=bool)
    merged[part[large[1:][piece[large[1:]] == piece[large[:-1]]]]] = True
    lost = counted & ((kept == 0) | broken | merged)
    return int(counted.sum()), int(lost.sum())

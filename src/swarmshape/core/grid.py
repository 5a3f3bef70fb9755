"""Boolean grids shared by shapes and images: cropping to the ink and shrinking by area.

A grid here is indexed ``[row, col]`` with row 0 at the top, as an image is seen. Images are
read elsewhere (`swarmshape.io.bitmap`); these operations are numpy only, so the core can shrink
a shape to fewer robots while it runs.
"""

from __future__ import annotations

import numpy as np


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

    Shrinking, each output cell averages the pixels whose centres fall in its box, first along
    rows and then along columns, in float32 between the passes: the filter Pillow calls BOX, so
    shapes shrink the same way images are loaded. Growing, each cell takes the pixel under its
    centre, so a small icon becomes the same picture in bigger blocks.
    """
    height, width = fraction.shape
    factor = long_side / max(height, width)
    size = (max(1, round(width * factor)), max(1, round(height * factor)))
    if factor >= 1.0:
        rows = np.minimum(((np.arange(size[1]) + 0.5) * height / size[1]).astype(int), height - 1)
        cols = np.minimum(((np.arange(size[0]) + 0.5) * width / size[0]).astype(int), width - 1)
        return fraction[np.ix_(rows, cols)] >= 0.5
    shrunk = fraction.astype(np.float32)
    if size[0] != width:
        shrunk = _box_average(shrunk, size[0], axis=1)
    if size[1] != height:
        shrunk = _box_average(shrunk, size[1], axis=0)
    return shrunk >= 0.5


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

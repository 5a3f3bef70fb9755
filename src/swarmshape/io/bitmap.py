"""Images in, boolean grids out (and back): the only module that reads or writes bitmaps.

A grid is a 2-D ``bool`` array indexed ``[row, col]`` with row 0 at the top, exactly as the
image is seen; ``True`` marks a cell of the shape ("ink").
"""

from __future__ import annotations

import os
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, PngImagePlugin, UnidentifiedImageError

from swarmshape.core.grid import (
    Likeness,
    bounding_box,
    crop,
    likeness,
    resample,
    resized,
    sized,
)
from swarmshape.core.world import MAX_AGENTS, MAX_ARENA_CELLS, ROOM_PER_AGENT
from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write, readable_file

DEFAULT_CELLS = 32
"""Fewest cells across a picture larger than this is given when none is asked for (smaller
pictures keep one cell per pixel); more when its parts need them (`chosen_cells`)."""

DETAIL = 4
"""Pixels across a cell in the reference a grid is compared with: a stroke narrower than half
a cell can never be ink, and the reference resolves half of that."""

DEFAULT_THRESHOLD = 0.5

FORMATS = ("PNG", "GIF", "BMP", "JPEG", "WEBP")
"""The raster formats swarmshape reads, recognised by their content, not their name."""

MAX_PIXELS = 25_000_000
"""Images with more pixels are refused from their header, before decoding (~0.6 GB to read)."""

EDITOR_TAG = "swarmshape-one-cell-per-pixel"

BLOCK = 2**20
"""Pixels whose ink is decided at a time (in doubles: 40 MB)."""
DARK_BORDER = 0.9
"""Share of dark border pixels that means "dark background" (a shape may touch the border)."""

MAX_FIT = 4096
"""Longest side ``--fit agents`` tries (a million robots need about 1,130 across)."""

DECODING_ERRORS = (OSError, SyntaxError, ValueError, EOFError, IndexError, TypeError, struct.error,
                   ZeroDivisionError, RuntimeError)  # fmt: skip
"""What Pillow's decoders raise on damaged files (each is turned into one line)."""


class BitmapError(InputError):
    """An image that cannot become a shape; the message says which file and why."""


class ShapeWarning(UserWarning):
    """The image became a shape, but not the one the picture suggests; the message says why
    and which option helps."""


@dataclass(frozen=True, eq=False)
class Picture:
    """An image's ink per pixel, cropped to the ink, before it is sized into cells."""

    path: Path
    ink: np.ndarray
    one_cell_per_pixel: bool
    near_threshold: float
    """Share of opaque pixels within 0.1 of the threshold: high for a low-contrast photo."""


def load_grid(
    path: str | os.PathLike[str],
    *,
    cells: int | None = None,
    threshold: float = DEFAULT_THRESHOLD,
    invert: bool = False,
) -> np.ndarray:
    """Read an image and return its ink as a cropped boolean grid, `cells` across its long
    side (None: the fewest that keep the picture, `chosen_cells`).

    Transparent pixels are never ink. Among opaque pixels, ink is the darker side of
    ``threshold`` (luminance 0..1) on a light background; a border at least 90 % dark with
    light pixels inside means a dark background and light ink; ``invert`` forces light ink.
    Larger images are shrunk by area averaging (a cell is ink when at least half of it is),
    smaller ones grown cell for pixel; drawings saved by the editor keep one cell per pixel.
    """
    return grid_of(read_picture(path, threshold=threshold, invert=invert), cells)


def read_picture(
    path: str | os.PathLike[str], *, threshold: float = DEFAULT_THRESHOLD, invert: bool = False
) -> Picture:
    """The image's ink, or one line saying why there is none to read."""
    path = Path(path)
    if not 0.0 <= threshold <= 1.0:  # as the setting says (`RunConfig.threshold`)
        raise BitmapError(f"--threshold must be from 0 to 1, got {threshold}")
    rgba, one_cell_per_pixel = _open_rgba(path)
    ink, near = ink_of(rgba, threshold=threshold, invert=invert)
    del rgba  # the ink is what is kept
    if not ink.any():
        hint = "try --invert" if near < 0.5 else "try another --threshold or --invert"
        raise BitmapError(f"{path}: no shape found (the image has no ink; {hint})")
    return Picture(path, bounding_box(ink), one_cell_per_pixel, near)


class _Sizes:
    """A picture's grids and their likeness at the sizes tried (`chosen`), each reference of
    the picture made once."""

    def __init__(self, picture: Picture) -> None:
        self.picture = picture
        self.long_side = max(picture.ink.shape)
        self.references: dict[int, np.ndarray] = {}

    def grid(self, cells: int) -> np.ndarray:
        """The grid `cells` across, before cropping (refused if larger than any arena); the
        editor's drawings keep one cell per pixel, whatever is asked."""
        ink = self.picture.ink
        cells = self.long_side if self.picture.one_cell_per_pixel else cells
        rows, cols = sized(ink.shape, cells)
        if rows * cols > MAX_ARENA_CELLS:  # before the grid is made: it would not fit in memory
            raise BitmapError(
                f"{self.picture.path}: --cells {cells:,} makes a grid of {max(rows, cols):,}x"
                f"{min(rows, cols):,} cells, more than the {MAX_ARENA_CELLS:,} of the largest "
                "arena; lower --cells"
            )
        return resample(ink, cells)

    def likeness(self, cells: int, grid: np.ndarray | None = None) -> Likeness:
        """How much of the picture its grid `cells` across keeps."""
        grid = self.grid(cells) if grid is None else grid
        # at least DETAIL pixels a cell, on a ladder of powers of two: the sizes a bisection
        # tries between two doublings share one reference, made from the picture itself
        across = min(self.long_side, DETAIL * 2 ** (cells - 1).bit_length())
        if across not in self.references:
            ink = self.picture.ink
            self.references[across] = resized(ink, sized(ink.shape, across))
        return likeness(self.references[across], grid, DEFAULT_CELLS)

    def largest(self) -> int:
        """The most cells across whose grid, with the robots for its ink and their room, fits
        the largest arena (and the picture's own size: a larger grid adds nothing)."""
        ink = self.picture.ink
        share = float(ink.mean())
        box = min(MAX_ARENA_CELLS / max(1.0, share * (1 + ROOM_PER_AGENT)), MAX_AGENTS / share)
        low, high = 1, self.long_side
        while low < high:  # the grid's cells grow with its long side
            middle = (low + high + 1) // 2
            low, high = (
                (middle, high) if np.prod(sized(ink.shape, middle)) <= box else (low, middle - 1)
            )
        return low

    def chosen(self) -> tuple[int, Likeness | None]:
        """The fewest cells across, from `DEFAULT_CELLS` up, whose grid keeps the picture, and
        its likeness (None for a picture kept one cell per pixel); the largest size when none
        does. Sizes double until one keeps it, then a bisection finds the first to within one
        cell in `DEFAULT_CELLS` (3 %: finer than the coarsest grid tells apart)."""
        if self.picture.one_cell_per_pixel or self.long_side <= DEFAULT_CELLS:
            return self.long_side, None
        largest = self.largest()
        cells = min(DEFAULT_CELLS, largest)
        low = cells - 1  # below the fewest: no bisection unless a larger size is needed
        found = self.likeness(cells)
        while not found.kept and cells < largest:
            low, cells = cells, min(2 * cells, largest)
            found = self.likeness(cells)
        while found.kept and cells - low > max(1, cells // DEFAULT_CELLS):
            middle = (low + cells) // 2
            tried = self.likeness(middle)
            low, cells, found = (low, middle, tried) if tried.kept else (middle, cells, found)
        return cells, found


def chosen_cells(picture: Picture) -> int:
    """The cells across that `grid_of` gives `picture` when none are asked for: the fewest, from
    `DEFAULT_CELLS` up to the largest arena, whose grid keeps its parts and outline
    (`Likeness`); pictures no larger, and the editor's drawings, keep one cell per pixel."""
    return _Sizes(picture).chosen()[0]


def grid_of(picture: Picture, cells: int | None) -> np.ndarray:
    """The picture as a grid `cells` across (None: `chosen_cells`); a warning when the grid
    loses much of the picture, naming the size that keeps it."""
    if cells is not None and cells < 1:
        raise BitmapError(f"--cells must be at least 1, got {cells}")
    sizes = _Sizes(picture)
    if cells is None:
        cells, found = sizes.chosen()
        grid = sizes.grid(cells)
    else:
        grid = sizes.grid(cells)
        exact = picture.one_cell_per_pixel or cells >= sizes.long_side  # grown cell for pixel
        found = None if exact or not grid.any() else sizes.likeness(cells, grid)
    if not grid.any():
        raise BitmapError(f"{picture.path}: the shape vanishes at {cells} cells across; "
                          f"{_help(picture, sizes, cells)}")  # fmt: skip
    kept = int(grid.sum())
    if kept <= 2 < picture.ink.sum():  # however like the picture, no shape for a swarm
        lost = f"the whole picture became {kept} cell{'' if kept == 1 else 's'}"
    elif found is not None and not found.kept:
        lost = f"at {cells} cells across the shape loses {found.losses()}"
    else:
        return crop(grid)
    warnings.warn(
        f"{picture.path}: {lost}; {_help(picture, sizes, cells)}", ShapeWarning, stacklevel=2
    )
    return crop(grid)


def grid_for(picture: Picture, robots: int) -> np.ndarray:
    """The largest grid of the picture with at most `robots` cells (``--fit agents``)."""
    sizes = _Sizes(picture)

    def count(cells: int) -> int:
        return int(sizes.grid(cells).sum())

    low, high = 1, 2
    while count(high) <= robots and high < MAX_FIT:
        low, high = high, 2 * high
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (middle, high) if count(middle) <= robots else (low, middle)
    if count(low) == 0:
        raise BitmapError(f"{picture.path}: too few robots ({robots}) to draw any of its shape")
    return crop(sizes.grid(low))


def _help(picture: Picture, sizes: _Sizes, cells: int) -> str:
    """The option most likely to bring the shape back: the cells that keep the picture, or for
    a low-contrast image (whose ink is noise near the threshold), the threshold."""
    if picture.near_threshold >= 0.5:
        return "this is a low-contrast image: move --threshold (0..1) toward its grey"
    keeps, found = sizes.chosen()
    if found is not None and not found.kept:
        return f"no size up to the largest arena's ({keeps} cells across) keeps it"
    return f"raise --cells to {keeps} to keep it" if keeps > cells else f"--cells {keeps} keeps it"


def _open_rgba(path: Path) -> tuple[np.ndarray, bool]:
    """Pixels as 8-bit RGBA, and whether the editor wrote the file (one cell per pixel)."""
    readable_file(path, "an image or a .toml scenario", BitmapError)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow's remarks are not the user's business
            with Image.open(path, formats=FORMATS) as image:
                width, height = image.size
                if width * height > MAX_PIXELS:
                    raise BitmapError(
                        f"{path}: image too large ({width}x{height} pixels, over "
                        f"{MAX_PIXELS:,}); shrink it first"
                    )
                image.seek(0)  # first frame of an animation
                rgba = np.asarray(image.convert("RGBA"))  # 4 bytes a pixel, as they come
                return rgba, image.info.get(EDITOR_TAG) == "1"
    except UnidentifiedImageError:
        formats = ", ".join(FORMATS[:-1]) + f" or {FORMATS[-1]}"
        raise BitmapError(f"{path}: not an image swarmshape reads ({formats})") from None
    except Image.DecompressionBombError:  # Pillow's own, far larger limit, met on opening
        raise BitmapError(
            f"{path}: image too large (over {MAX_PIXELS:,} pixels); shrink it first"
        ) from None
    except DECODING_ERRORS as error:
        raise BitmapError(f"{path}: cannot read image ({_reason(error)})") from None
    except MemoryError:  # a damaged length, read at once: a PNG chunk claiming 4 GB
        raise BitmapError(
            f"{path}: cannot read image (it asks for more memory than there is; damaged?)"
        ) from None


def _reason(error: BaseException) -> str:
    return str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__


def ink_of(rgba: np.ndarray, *, threshold: float, invert: bool) -> tuple[np.ndarray, float]:
    """Per pixel whether it is ink, decided as `load_grid` documents from 8-bit RGBA; and the
    share of opaque pixels within 0.1 of the threshold (high for a low-contrast photo).

    Worked out `BLOCK` pixels at a time, so beside the pixels themselves it takes two bytes a
    pixel (a 5000x5000 picture took 1.7 GB in doubles before it was found to have no ink)."""
    height, width = rgba.shape[:2]
    flat = rgba.reshape(-1, 4)
    light = np.empty(len(flat), dtype=bool)
    opaque = np.empty(len(flat), dtype=bool)
    near = 0
    for start in range(0, len(flat), BLOCK):
        block_light, block_opaque, luminance = _decided(flat[start : start + BLOCK], threshold)
        light[start : start + BLOCK], opaque[start : start + BLOCK] = block_light, block_opaque
        near += int((np.abs(luminance[block_opaque] - threshold) < 0.1).sum())
    light, opaque = light.reshape(height, width), opaque.reshape(height, width)
    border = np.concatenate([opaque[0], opaque[-1], opaque[:, 0], opaque[:, -1]])
    border_light = np.concatenate([light[0], light[-1], light[:, 0], light[:, -1]])
    if invert:
        ink = light
    elif not border.any():
        ink = opaque  # a cut-out on a transparent canvas: every opaque pixel
    elif np.mean(~border_light[border]) >= DARK_BORDER and (light & opaque).any():
        ink = light  # a dark background with something light on it
    else:
        ink = ~light
    seen = int(opaque.sum())
    return ink & opaque, near / seen if seen else 0.0


def _decided(pixels: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For 8-bit RGBA `pixels` ``(k, 4)``: which are lighter than `threshold`, which are
    opaque, and their luminance (0..1)."""
    values = pixels.astype(np.float64) / 255.0
    luminance = values[:, :3] @ np.array([0.299, 0.587, 0.114])
    return luminance > threshold, values[:, 3] >= 0.5, luminance


def save_grid(grid: np.ndarray, path: str | os.PathLike[str]) -> None:
    """Write black ink on white as a 1-bit PNG, atomically, so `load_grid` reads it back exactly.

    The PNG carries a text chunk saying it has one cell per pixel, so it is never shrunk to
    ``--cells`` when it is loaded again, however large it was painted.
    """
    image = Image.fromarray(np.where(grid, 0, 255).astype(np.uint8)).convert("1")
    info = PngImagePlugin.PngInfo()
    info.add_text(EDITOR_TAG, "1")
    atomic_write(path, lambda tmp: image.save(tmp, format="PNG", pnginfo=info))

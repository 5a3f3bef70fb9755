"""Images in, boolean grids out (and back): the only module that reads or writes bitmaps.

A grid is a 2-D ``bool`` array indexed ``[row, col]`` with row 0 at the top, exactly as the
image is seen; ``True`` marks a cell of the shape ("ink").
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image, PngImagePlugin, UnidentifiedImageError

from swarmshape.core.grid import bounding_box, crop, resample
from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write

DEFAULT_CELLS = 32
"""Long side of the grid, in cells, when the image is larger: ~300-700 cells for a silhouette."""

DEFAULT_THRESHOLD = 0.5

EDITOR_TAG = "swarmshape-one-cell-per-pixel"

DARK_BORDER = 0.9
"""Share of dark border pixels that means "dark background" (a shape may touch the border)."""


class BitmapError(InputError):
    """An image that cannot become a shape; the message says which file and why."""


def load_grid(
    path: str | os.PathLike[str],
    *,
    cells: int = DEFAULT_CELLS,
    threshold: float = DEFAULT_THRESHOLD,
    invert: bool = False,
) -> np.ndarray:
    """Read any image Pillow can open and return its ink as a cropped boolean grid.

    Transparent pixels are never ink. Among opaque pixels, ink is the darker side of
    ``threshold`` (luminance 0..1) on a light background; a border at least 90 % dark with
    light pixels inside means a dark background and light ink; ``invert`` forces light ink.
    Images wider or taller than ``cells`` are downscaled by area averaging, so a cell is ink
    when at least half of it is.
    """
    path = Path(path)
    if cells < 1:
        raise BitmapError(f"--cells must be at least 1, got {cells}")
    if not 0.0 < threshold < 1.0:
        raise BitmapError(f"--threshold must be between 0 and 1, got {threshold}")
    rgba, one_cell_per_pixel = _open_rgba(path)
    if one_cell_per_pixel:
        cells = max(cells, *rgba.shape[:2])
    ink = ink_fraction(rgba, threshold=threshold, invert=invert)
    if not ink.any():
        raise BitmapError(f"{path}: no shape found (the image has no ink; try --invert)")
    grid = crop(resample(bounding_box(ink), cells))
    if not grid.any():
        raise BitmapError(f"{path}: the shape vanishes at --cells {cells}; raise --cells")
    return grid


def _open_rgba(path: Path) -> tuple[np.ndarray, bool]:
    """Pixels as RGBA floats, and whether the editor wrote the file (one cell per pixel)."""
    if not path.exists():
        raise BitmapError(f"{path}: no such file")
    if path.is_dir():
        raise BitmapError(f"{path}: is a directory, expected an image or a .toml scenario")
    try:
        with Image.open(path) as image:
            image.seek(0)  # first frame of an animation
            rgba = np.asarray(image.convert("RGBA"), dtype=np.float64) / 255.0
            return rgba, image.info.get(EDITOR_TAG) == "1"
    except UnidentifiedImageError:
        raise BitmapError(f"{path}: not an image Pillow can read") from None
    except Image.DecompressionBombError:
        limit = Image.MAX_IMAGE_PIXELS
        raise BitmapError(f"{path}: image too large (over {limit} pixels)") from None
    except OSError as error:
        raise BitmapError(f"{path}: cannot read image ({error})") from None


def ink_fraction(rgba: np.ndarray, *, threshold: float, invert: bool) -> np.ndarray:
    """Per pixel 1.0 for ink, 0.0 for background, decided as `load_grid` documents."""
    opaque = rgba[..., 3] >= 0.5
    luminance = rgba[..., :3] @ np.array([0.299, 0.587, 0.114])
    border = np.concatenate([opaque[0], opaque[-1], opaque[:, 0], opaque[:, -1]])
    border_lum = np.concatenate([luminance[0], luminance[-1], luminance[:, 0], luminance[:, -1]])
    light = luminance > threshold
    if invert:
        ink = light
    elif not border.any():
        ink = np.ones_like(opaque)  # a cut-out on a transparent canvas: every opaque pixel
    elif np.mean(border_lum[border] <= threshold) >= DARK_BORDER and (light & opaque).any():
        ink = light  # a dark background with something light on it
    else:
        ink = ~light
    return (ink & opaque).astype(np.float64)


def save_grid(grid: np.ndarray, path: str | os.PathLike[str]) -> None:
    """Write black ink on white as a 1-bit PNG, atomically, so `load_grid` reads it back exactly.

    The PNG carries a text chunk saying it has one cell per pixel, so it is never shrunk to
    ``--cells`` when it is loaded again, however large it was painted.
    """
    image = Image.fromarray(np.where(grid, 0, 255).astype(np.uint8)).convert("1")
    info = PngImagePlugin.PngInfo()
    info.add_text(EDITOR_TAG, "1")
    atomic_write(path, lambda tmp: image.save(tmp, format="PNG", pnginfo=info))

"""Pictures like a user's, drawn with Pillow: a word, a logo, a line drawing, a ring, a photo.

Each is drawn at the size a user's file would have, with the pieces and holes it is known to
have, so a test can ask whether a shape keeps them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from swarmshape.ui.render import FONT_FILE


def word(path: Path, text: str = "debian 12") -> Path:
    """Black text on white in Pillow's own font, 80 pixels high: letters with holes (d, e,
    b, a), thin strokes, and gaps between letters that must stay gaps."""
    font = ImageFont.load_default(size=80)
    *_, right, bottom = font.getbbox(text)
    image = Image.new("L", (right + 20, bottom + 20), 255)
    ImageDraw.Draw(image).text((10, 10), text, font=font, fill=0)
    image.save(path)
    return path


def logo(path: Path) -> Path:
    """A ten-letter word logo in bold, seven times as wide as it is high (the shipped DejaVu
    Sans at 120 pixels, its strokes 2 pixels thicker, widened by a tenth): its smaller
    letters have less ink than 4 cells of a grid 32 cells across, its counters less than 1."""
    font = ImageFont.truetype(FONT_FILE, 120)
    *_, right, bottom = font.getbbox("swarmshape", stroke_width=2)
    image = Image.new("L", (right + 20, bottom + 20), 255)
    ImageDraw.Draw(image).text((10, 10), "swarmshape", font=font, fill=0, stroke_width=2)
    image.resize((round(image.width * 1.1), image.height)).save(path)
    return path


LINES = (3, 2)
"""Pieces and holes of `lines`: a circle, a cross and a rectangle; the circle's and the
rectangle's insides."""


def lines(path: Path) -> Path:
    """A line drawing, 600 x 450, every stroke 3 pixels wide (a two-hundredth of its width)."""
    image = Image.new("L", (600, 450), 255)
    draw = ImageDraw.Draw(image)
    draw.ellipse((50, 50, 250, 250), outline=0, width=3)
    draw.line((300, 100, 550, 400), fill=0, width=3)
    draw.line((300, 400, 550, 100), fill=0, width=3)
    draw.rectangle((60, 300, 260, 420), outline=0, width=3)
    image.save(path)
    return path


RING = (1, 1)


def ring(path: Path) -> Path:
    """A filled disc, 432 pixels across, with a round hole of 120 in its middle."""
    image = Image.new("L", (512, 512), 255)
    draw = ImageDraw.Draw(image)
    draw.ellipse((40, 40, 472, 472), fill=0)
    draw.ellipse((196, 196, 316, 316), fill=255)
    image.save(path)
    return path


PHOTO = (1, 0)


def photo(path: Path, seed: int = 1) -> Path:
    """A photo-like 1600 x 1200 greyscale: a smooth gradient, darker round one point, with a
    ripple and grain, so the ink is one soft-edged region."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:1200, 0:1600] / 1600
    lum = 0.25 + 0.6 * np.hypot(x - 0.45, y - 0.4) + 0.1 * np.sin(9 * x) * np.cos(7 * y)
    lum += rng.normal(0, 0.03, lum.shape)
    Image.fromarray((np.clip(lum, 0, 1) * 255).astype(np.uint8)).save(path)
    return path

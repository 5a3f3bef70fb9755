"""Draw the shipped shapes in shapes/ with Pillow (run once; the PNGs are committed).

The paper's three shapes are drawn one pixel per cell, so they load exactly as drawn. The
richer ones are drawn large and smooth, so loading them also exercises downscaling. The horse
is scikit-image's public-domain silhouette (`skimage.data.horse`), a photo-like outline for the
benchmark; scikit-image is needed only to draw it (`pip install scikit-image`), never to run.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

SHAPES = Path(__file__).resolve().parent.parent / "shapes"
INK, PAPER = 0, 255


def cells(width: int, height: int, boxes: list[tuple[int, int, int, int]]) -> Image.Image:
    """A one-pixel-per-cell image with ink in the given inclusive (x0, y0, x1, y1) boxes."""
    image = Image.new("L", (width, height), PAPER)
    draw = ImageDraw.Draw(image)
    for box in boxes:
        draw.rectangle(box, fill=INK)
    return image


def star(size: int = 512, points: int = 5) -> Image.Image:
    image = Image.new("L", (size, size), PAPER)
    centre, outer, inner = size / 2, size * 0.48, size * 0.2
    corners = []
    for k in range(2 * points):
        radius = outer if k % 2 == 0 else inner
        angle = math.pi * k / points - math.pi / 2
        corners.append((centre + radius * math.cos(angle), centre + radius * math.sin(angle)))
    ImageDraw.Draw(image).polygon(corners, fill=INK)
    return image


def disc(size: int = 512) -> Image.Image:
    """The round shape the benchmarks use: no corners, arms or holes, so what a strategy
    costs on it is the swarm's own traffic."""
    image = Image.new("L", (size, size), PAPER)
    ImageDraw.Draw(image).ellipse((8, 8, size - 8, size - 8), fill=INK)
    return image


def ring(size: int = 512) -> Image.Image:
    """A dark ring on a transparent canvas: exercises alpha and a shape with a hole."""
    image = Image.new("RGBA", (size, size), (0, 0, 0, 0))
    draw = ImageDraw.Draw(image)
    draw.ellipse((8, 8, size - 8, size - 8), fill=(30, 30, 30, 255))
    draw.ellipse((size * 0.3, size * 0.3, size * 0.7, size * 0.7), fill=(0, 0, 0, 0))
    return image


def letter_s(size: int = 512) -> Image.Image:
    """A blocky white S on black: exercises dark-background detection."""
    image = Image.new("L", (size * 3 // 4, size), 0)
    draw = ImageDraw.Draw(image)
    w, h, t = size * 3 // 4, size, size // 6
    for box in (
        (t // 2, t // 2, w - t // 2, t // 2 + t),
        (t // 2, t // 2, t // 2 + t, h // 2 + t // 2),
        (t // 2, h // 2 - t // 2, w - t // 2, h // 2 + t // 2),
        (w - t // 2 - t, h // 2 - t // 2, w - t // 2, h - t // 2),
        (t // 2, h - t // 2 - t, w - t // 2, h - t // 2),
    ):
        draw.rounded_rectangle(box, radius=t // 3, fill=255)
    return image


def horse() -> Image.Image | None:
    """The horse silhouette, black on white, or None without scikit-image."""
    try:
        from skimage import data
    except ImportError:
        return None
    return Image.fromarray(np.where(data.horse(), PAPER, INK).astype(np.uint8))


def letter_k(height: int = 44) -> Image.Image:
    """A block letter K of about a thousand cells, one pixel per cell and hole-free: the
    shape of Rubenstein, Cornejo and Nagpal's thousand-Kilobot self-assembly (Science 2014)."""
    width, stem = height * 3 // 4, height // 4
    image = Image.new("L", (width, height), PAPER)
    draw = ImageDraw.Draw(image)
    draw.rectangle((0, 0, stem - 1, height - 1), fill=INK)
    middle, arm = height // 2, stem + 1
    draw.polygon(
        [(stem - 1, middle - arm), (width - arm, 0), (width - 1, 0), (stem - 1, middle + arm // 2)],
        fill=INK,
    )
    draw.polygon(
        [(stem - 1, middle - arm // 2), (width - 1, height - 1), (width - arm, height - 1),
         (stem - 1, middle + arm)],
        fill=INK,
    )  # fmt: skip
    return image


def main() -> None:
    SHAPES.mkdir(exist_ok=True)
    cells(16, 1, [(0, 0, 15, 0)]).save(SHAPES / "line.png")
    cells(8, 8, [(0, 0, 7, 7)]).save(SHAPES / "square.png")
    cells(6, 6, [(0, 0, 5, 5)]).save(SHAPES / "small-square.png")
    cells(12, 12, [(0, 0, 2, 11), (9, 0, 11, 11), (0, 9, 11, 11)]).rotate(180).save(
        SHAPES / "horseshoe.png"
    )
    star().save(SHAPES / "star.png")
    ring().save(SHAPES / "ring.png")
    disc().save(SHAPES / "disc.png")
    letter_s().save(SHAPES / "letter-s.png")
    cells(50, 20, [(0, 0, 49, 19)]).save(SHAPES / "block.png")
    silhouette = horse()
    if silhouette is None:
        print("scikit-image is not installed: shapes/horse.png left as it is")
    else:
        silhouette.save(SHAPES / "horse.png")
    letter_k().save(SHAPES / "letter-k.png")


if __name__ == "__main__":
    main()

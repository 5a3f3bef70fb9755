from __future__ import annotations

import resource
import subprocess
import sys
import tracemalloc
import warnings

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from swarmshape.core.grid import KEPT, PART, crop, resample
from swarmshape.io.bitmap import (
    DEFAULT_CELLS,
    BitmapError,
    ShapeWarning,
    chosen_cells,
    grid_for,
    load_grid,
    read_picture,
    save_grid,
)
from swarmshape.io.bitmap import _Sizes as Sizes  # the likeness each size is judged by
from tests import pictures


def write(path, array, mode=None):
    Image.fromarray(np.asarray(array, dtype=np.uint8), mode).save(path)
    return path


def test_dark_ink_on_light_background_is_cropped(tmp_path):
    image = np.full((10, 12), 255)
    image[2:5, 3:9] = 0
    grid = load_grid(write(tmp_path / "a.png", image))
    assert grid.shape == (3, 6)
    assert grid.all()


def test_light_ink_on_dark_background_is_detected(tmp_path):
    image = np.zeros((10, 10))
    image[4:6, 2:8] = 255
    grid = load_grid(write(tmp_path / "a.png", image))
    assert grid.shape == (2, 6) and grid.all()


def test_invert_forces_light_ink(tmp_path):
    image = np.full((6, 6), 255)
    image[1:3, 1:3] = 0
    grid = load_grid(write(tmp_path / "a.png", image), invert=True)
    assert grid.sum() == 36 - 4


def test_transparent_pixels_are_never_ink(tmp_path):
    rgba = np.zeros((8, 8, 4))
    rgba[..., 3] = 0  # transparent canvas
    rgba[2:6, 3:5] = (250, 250, 250, 255)  # a white cut-out is ink on a transparent canvas
    grid = load_grid(write(tmp_path / "a.png", rgba, "RGBA"))
    assert grid.shape == (4, 2) and grid.all()


def test_transparent_black_pixels_on_white_are_not_ink(tmp_path):
    rgba = np.full((6, 6, 4), 255)
    rgba[1:3, 1:3] = (0, 0, 0, 255)
    rgba[4, 4] = (0, 0, 0, 0)  # black but transparent
    grid = load_grid(write(tmp_path / "a.png", rgba, "RGBA"))
    assert grid.shape == (2, 2) and grid.all()


def test_large_image_is_area_averaged_to_cells(tmp_path):
    image = np.full((100, 120), 255)
    image[:, :100] = 0
    image[:50, 100:] = 0
    grid = load_grid(write(tmp_path / "a.png", image), cells=12)
    expected = np.ones((10, 12), dtype=bool)
    expected[5:, 10:] = False
    assert np.array_equal(grid, expected)


def test_a_cell_is_ink_when_at_least_half_of_it_is(tmp_path):
    image = np.full((40, 30), 255)
    image[:, :20] = 0
    image[:20, 20:26] = 0  # 60 % of the cells in the upper right
    image[20:, 26:] = 0  # 40 % of the cells in the lower right
    grid = load_grid(write(tmp_path / "a.png", image), cells=4)
    assert grid.tolist() == [[True, True, True]] * 2 + [[True, True, False]] * 2


def test_gif_first_frame_and_other_formats(tmp_path):
    frames = [Image.new("L", (5, 5), 255) for _ in range(2)]
    frames[0].paste(0, (1, 1, 3, 3))
    frames[0].save(tmp_path / "a.gif", save_all=True, append_images=frames[1:])
    assert load_grid(tmp_path / "a.gif").shape == (2, 2)
    image = np.full((6, 6), 255)
    image[2:4, 2:4] = 0
    for suffix in ("bmp", "webp"):
        Image.fromarray(image.astype(np.uint8)).save(tmp_path / f"a.{suffix}", lossless=True)
        assert load_grid(tmp_path / f"a.{suffix}").shape == (2, 2)


def test_save_then_load_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(3)
    grid = rng.random((9, 13)) < 0.5
    grid[0, 0] = grid[-1, -1] = True  # keep the bounding box, so cropping changes nothing
    save_grid(grid, tmp_path / "g.png")
    assert np.array_equal(load_grid(tmp_path / "g.png"), grid)


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("missing.png", None, "no such file"),
        ("text.png", b"this is not an image", "not an image"),
        ("blank.png", "white", "no shape found"),
    ],
)
def test_bad_images_say_what_is_wrong(tmp_path, name, content, message):
    path = tmp_path / name
    if content == "white":
        write(path, np.full((5, 5), 255))
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(BitmapError, match=message):
        load_grid(path)


def test_a_directory_is_not_an_image(tmp_path):
    with pytest.raises(BitmapError, match="directory"):
        load_grid(tmp_path)


def test_a_small_image_grows_to_the_cells_asked_for_and_stays_its_size_otherwise(tmp_path):
    image = np.full((4, 8), 255, dtype=np.uint8)
    image[1:3, 2:6] = 0
    path = write(tmp_path / "icon.png", image)
    assert load_grid(path).shape == (2, 4), "no --cells: the image's own size"
    grown = load_grid(path, cells=12)
    assert grown.shape == (6, 12) and grown.all()


def test_a_shape_that_keeps_little_of_its_picture_says_to_raise_cells(tmp_path):
    image = np.full((200, 200), 255, dtype=np.uint8)
    image[::5, :] = 0  # thin lines, a fifth of the picture, vanish when shrunk ...
    image[:40, :40] = 0  # ... and only this block is left
    path = write(tmp_path / "lines.png", image)
    with pytest.warns(ShapeWarning, match="raise --cells"):
        load_grid(path, cells=10)
    assert load_grid(path, cells=200).sum() > 8_000


def test_a_low_contrast_picture_is_told_about_the_threshold(tmp_path):
    image = np.full((60, 60), 150, dtype=np.uint8)  # light grey ...
    image[10:50, 10:50] = 135  # ... and a slightly darker grey square, both above 0.5
    path = write(tmp_path / "grey.png", image)
    with pytest.raises(BitmapError, match="another --threshold"):
        load_grid(path)
    assert load_grid(path, threshold=0.5 * (135 + 150) / 255).sum() > 100


def test_a_picture_squeezed_into_a_cell_or_two_says_so(tmp_path):
    image = np.full((40, 40), 255, dtype=np.uint8)
    image[5:11, 5:11] = 0
    with pytest.warns(ShapeWarning, match="the whole picture became 1 cell"):
        assert load_grid(write(tmp_path / "speck.gif", image), cells=1).sum() == 1


def test_the_format_comes_from_the_content_not_the_name(tmp_path):
    image = np.full((10, 10), 255, dtype=np.uint8)
    image[2:8, 2:8] = 0
    Image.fromarray(image).save(tmp_path / "really.png", format="JPEG")
    assert load_grid(tmp_path / "really.png").sum() == 36
    Image.fromarray(image).save(tmp_path / "tiff.png", format="TIFF")
    with pytest.raises(BitmapError, match="not an image swarmshape reads"):
        load_grid(tmp_path / "tiff.png")


def test_fit_finds_the_largest_shape_the_robots_can_fill(tmp_path):
    image = np.zeros((10, 10), dtype=np.uint8)  # a filled block
    picture = read_picture(write(tmp_path / "block.png", image))
    for robots in (1, 50, 400, 1000):
        grid = grid_for(picture, robots)
        assert grid.sum() <= robots
        side = grid.shape[0]
        assert (side + 1) ** 2 > robots, "one cell more across would not fit"


@pytest.mark.parametrize("cells", [5001, 10**11])
def test_cells_beyond_the_largest_arena_are_refused_before_the_grid_is_made(tmp_path, cells):
    """Found by the fuzz: --cells 99999999999 asked numpy for 47 GB (an internal error), and
    --cells 100000 took 5.6 GB and 9 s to say there were too many robots."""
    path = write(tmp_path / "square.png", np.zeros((6, 6)))
    tracemalloc.start()
    try:
        with pytest.raises(BitmapError, match=f"--cells {cells:,} makes a grid of"):
            load_grid(path, cells=cells)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 10_000_000
    assert load_grid(path, cells=5000).shape == (5000, 5000)


def test_a_png_claiming_gigabytes_is_one_clear_error_under_a_memory_limit(tmp_path):
    """Found by the long fuzz (seed 11, case 858): one flipped bit made a 71-byte PNG's IDAT
    chunk claim 4 GB, which Pillow reads at once; under a memory limit (a container, ulimit
    -v) its MemoryError was an internal error."""
    path = tmp_path / "claims.png"
    Image.new("1", (5, 3)).save(path)
    data = bytearray(path.read_bytes())
    data[data.index(b"IDAT") - 4] = 0xFF  # the length's top byte: 4 GB more
    path.write_bytes(bytes(data))
    code = "import sys; from swarmshape.cli import main; sys.exit(main(sys.argv[1:]))"
    result = subprocess.run(
        [sys.executable, "-c", code, str(path), "--preview"], capture_output=True, text=True,
        timeout=60, preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (2**30, 2**30)),
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert result.stderr == (
        f"swarmshape: error: {path}: cannot read image (it asks for more memory than there is; "
        "damaged?)\n"
    )


@pytest.mark.parametrize("size, out", [(13, 6), (15, 14), (19, 10), (25, 18), (1000, 7)])
def test_shrinking_averages_each_box_as_pillows_box_filter(size, out):
    """Pillow's boxes may leave a pixel between two boxes out: each box is summed on its own."""
    from swarmshape.core.grid import _box_average

    pixels = np.random.default_rng(size).random((3, size)).astype(np.float32)
    pillow = np.stack([np.asarray(Image.fromarray(row[None]).resize((out, 1), Image.BOX))[0]
                       for row in pixels])  # fmt: skip
    assert np.allclose(_box_average(pixels, out, axis=1), pillow, atol=1e-6)


def test_a_shape_that_vanishes_names_its_size_and_the_size_that_keeps_it(tmp_path):
    """Issue 29, case 13: without --cells this said "the shape vanishes at --cells None". Since
    issue 34 the default size keeps the picture, so only a size asked for can lose it all."""
    image = np.full((400, 400), 255)
    image[0, 0] = image[-1, -1] = 0  # two dots far apart: each a sliver of its cell
    path = write(tmp_path / "dots.png", image)
    keeps = chosen_cells(read_picture(path))
    with pytest.raises(
        BitmapError, match=f"vanishes at 32 cells across; raise --cells to {keeps} "
    ):
        load_grid(path, cells=32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_grid(path).sum() == load_grid(path, cells=keeps).sum() == 2


def pieces_and_holes(ink: np.ndarray, least: float = 0) -> tuple[int, int]:
    """8-connected pieces of ink and 4-connected holes (background off the border), counting
    those of at least `least` pixels."""
    labels, _ = ndimage.label(ink, np.ones((3, 3)))
    pieces = int((np.bincount(labels.ravel())[1:] >= max(least, 1)).sum())
    background, _ = ndimage.label(~ink)
    border = np.concatenate([background[0], background[-1], background[:, 0], background[:, -1]])
    area = np.bincount(background.ravel())
    area[np.unique(border)] = 0
    return pieces, int((area[1:] >= max(least, 1)).sum())


def iou_at_full_size(ink: np.ndarray, grid: np.ndarray) -> float:
    """The IoU of a picture's ink and `grid` scaled up to it, each pixel taking its cell."""
    rows = np.arange(ink.shape[0]) * grid.shape[0] // ink.shape[0]
    cols = np.arange(ink.shape[1]) * grid.shape[1] // ink.shape[1]
    scaled = grid[np.ix_(rows, cols)]
    return (scaled & ink).sum() / (scaled | ink).sum()


USERS = [("word", None, True), ("logo", None, True), ("lines", pictures.LINES, True),
         ("ring", pictures.RING, False), ("photo", pictures.PHOTO, False)]  # fmt: skip
"""Each picture, its pieces and holes when known, and whether 32 cells lose it."""


@pytest.mark.parametrize(("name", "known", "lost_at_32"), USERS)
def test_the_default_size_keeps_a_users_picture(tmp_path, name, known, lost_at_32):
    """Issue 34: at the old default (the long side, at most 32 cells) a word became 32 x 6
    cells and a line drawing scattered cells. Now the word's letters and holes, the drawing's
    strokes and the ring's hole are kept, and the shape shares more with the picture than it
    differs from it; a picture 32 cells keep is not made larger."""
    picture = read_picture(getattr(pictures, name)(tmp_path / f"{name}.png"))
    cells = chosen_cells(picture)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        grid = load_grid(picture.path)
    whole = resample(picture.ink, cells)
    assert np.array_equal(grid, crop(whole)) and max(whole.shape) == cells
    cell = (max(picture.ink.shape) / cells) ** 2
    counted, every = pieces_and_holes(picture.ink, PART * cell), pieces_and_holes(picture.ink)
    kept = pieces_and_holes(grid)
    for least, shown, most in zip(counted, kept, every, strict=True):
        assert least <= shown <= most, "none lost of 2x2 cells or more, none made up"
    assert kept == (known or kept)
    assert iou_at_full_size(picture.ink, whole) >= KEPT
    assert (cells > DEFAULT_CELLS) == lost_at_32
    assert (pieces_and_holes(resample(picture.ink, DEFAULT_CELLS)) != kept) == lost_at_32


@pytest.mark.parametrize("name", ["word", "logo", "lines"])
def test_a_grid_loses_no_more_parts_or_holes_than_the_picture_has(tmp_path, name):
    """Each part counts once, however many ways it is lost: counted per piece of the grid,
    the line drawing at 60 cells lost "3 of the picture's 2 parts", a word at 28 "4 of the
    picture's 2 holes"."""
    sizes = Sizes(read_picture(getattr(pictures, name)(tmp_path / f"{name}.png")))
    for cells in range(20, 160, 4):
        found = sizes.likeness(cells)
        assert 0 <= found.lost_parts <= found.parts and 0 <= found.lost_holes <= found.holes


@pytest.mark.parametrize("name", ["word", "lines"])
def test_too_few_cells_warn_with_the_size_that_keeps_the_picture(tmp_path, name):
    path = getattr(pictures, name)(tmp_path / f"{name}.png")
    keeps = chosen_cells(read_picture(path))
    with pytest.warns(ShapeWarning, match=f"at {keeps // 2} cells across the shape loses .*; "
                                          f"raise --cells to {keeps} to keep it$"):  # fmt: skip
        load_grid(path, cells=keeps // 2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_grid(path, cells=keeps)


def test_every_shipped_picture_loads_at_a_size_that_keeps_it(shapes):
    """Pictures of at most 32 pixels keep one cell per pixel; larger ones keep their look."""
    for path in sorted(shapes.glob("*.png")):
        picture = read_picture(path)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            grid = load_grid(path)
        long_side = max(picture.ink.shape)
        if long_side <= DEFAULT_CELLS:
            assert grid.shape == picture.ink.shape, path.name
        else:
            assert chosen_cells(picture) >= DEFAULT_CELLS, path.name


@pytest.mark.parametrize("threshold", [0.0, 1.0])
def test_the_thresholds_at_the_ends_of_the_range_the_setting_allows_are_read(threshold):
    """The setting takes 0 to 1; the reader refused both ends ("must be between 0 and 1")."""
    from swarmshape.config import RunConfig, bundled_shapes

    assert RunConfig(threshold=threshold).threshold == threshold
    assert load_grid(bundled_shapes() / "line.png", threshold=threshold).any()

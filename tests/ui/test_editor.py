"""The editor: canvas operations, and a person's clicks and keys posted as pygame events."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np
import pygame
import pytest
from PIL import Image

from swarmshape.config import bundled_shapes
from swarmshape.core.shape import Pose
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import blank_world
from swarmshape.io.bitmap import load_grid
from swarmshape.strategies import create
from swarmshape.ui.editor import HELP_LINES, HISTORY, PAINT, Canvas, data_folder
from swarmshape.ui.render import FLOOR, SEED_GREEN
from swarmshape.ui.viewer import Viewer
from tests.conftest import grid_from, world_of

# --- the canvas -------------------------------------------------------------------------


def test_a_fast_stroke_leaves_no_gaps():
    canvas = Canvas((20, 10))
    canvas.stroke((0, 0), (9, 3), 1, True)
    painted = canvas.cells
    assert len(painted) == 10 and sorted(painted[:, 0].tolist()) == list(range(10))
    steps = np.abs(np.diff(painted[np.argsort(painted[:, 0])], axis=0))
    assert (steps.max(axis=1) == 1).all(), "each cell touches the next"


def test_brush_size_and_erasing():
    canvas = Canvas((10, 10))
    canvas.stroke((5, 5), (5, 5), 3, True)
    assert canvas.grid.sum() == 9 and canvas.grid[4:7, 4:7].all()
    canvas.stroke((5, 5), (5, 5), 1, False)
    assert canvas.grid.sum() == 8 and not canvas.grid[5, 5]


def test_undo_and_redo_keep_at_least_a_hundred_steps():
    canvas = Canvas((200, 4))
    for x in range(150):
        canvas.checkpoint()
        canvas.stroke((x, 0), (x, 0), 1, True)
    assert HISTORY >= 100
    for _ in range(150):
        assert canvas.undo()
    assert not canvas.grid.any()
    assert not canvas.undo()
    assert canvas.redo() and canvas.grid.sum() == 1


def test_flood_fill_stays_inside_a_closed_outline():
    canvas = Canvas((9, 9))
    ring = grid_from("#####\n#...#\n#...#\n#####").T  # [x, y]
    canvas.grid[:5, :4] = ring
    canvas.fill((2, 1))
    assert canvas.grid[:5, :4].all() and canvas.grid.sum() == 20


def test_blocked_cells_are_never_painted():
    canvas = Canvas((5, 5))
    canvas.blocked[2, 2] = True
    canvas.stroke((0, 2), (4, 2), 1, True)
    assert canvas.grid.sum() == 4 and not canvas.grid[2, 2]


# --- a person at the editor -------------------------------------------------------------


def paper(world):
    return Swarm(world, create("optimal"), 1)


@pytest.fixture
def blank(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    view = Viewer(
        paper,
        blank_world((30, 20), Pose(3, 3), "untitled", (200, 60, 60)),
        title="untitled",
        start=False,
        shape_file=tmp_path / "drawn.png",
        size=(640, 480),
        fps=0,
    )
    yield view
    pygame.quit()


def pixel(view: Viewer, cell: tuple[int, int]) -> tuple[int, int]:
    return view.renderer.cell_rect(cell, view._world_area()).center


def drag(view: Viewer, start, end, button: int = 1) -> None:
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=pixel(view, start), button=button)
    )
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEMOTION, pos=pixel(view, end), rel=(0, 0), buttons=(1, 0, 0))
    )
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=pixel(view, end), button=button))
    view.tick()


def key(view: Viewer, code: int, mod: int = 0, text: str = "") -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=code, mod=mod, unicode=text))
    view.tick()


def test_a_stroke_paints_the_cells_under_it_and_undo_restores(blank):
    drag(blank, (10, 10), (20, 10))
    assert blank.editor.canvas.grid[10:21, 10].all() and blank.editor.canvas.grid.sum() == 11
    assert "*" in blank.status()
    drag(blank, (15, 10), (15, 10), button=3)
    assert not blank.editor.canvas.grid[15, 10]
    key(blank, pygame.K_z, pygame.KMOD_CTRL)
    assert blank.editor.canvas.grid[15, 10]
    key(blank, pygame.K_z, pygame.KMOD_CTRL)
    assert not blank.editor.canvas.grid.any()
    key(blank, pygame.K_y, pygame.KMOD_CTRL)
    assert blank.editor.canvas.grid.sum() == 11


def test_save_then_load_gives_back_the_same_shape(blank, tmp_path):
    drag(blank, (8, 8), (16, 12))
    drag(blank, (8, 14), (9, 14))
    key(blank, pygame.K_s, pygame.KMOD_CTRL)
    saved = load_grid(tmp_path / "drawn.png", cells=4)  # never shrunk: one cell per pixel
    assert np.array_equal(saved, blank.editor.shape().grid)
    assert "*" not in blank.status()


def test_save_as_asks_for_a_name_in_the_window(blank, tmp_path):
    drag(blank, (8, 8), (12, 8))
    key(blank, pygame.K_s, pygame.KMOD_CTRL | pygame.KMOD_SHIFT)
    assert "save as" in blank._second_line()
    for _ in range(len("drawn.png")):
        key(blank, pygame.K_BACKSPACE)
    for letter in "bar":
        key(blank, ord(letter), text=letter)
    key(blank, pygame.K_RETURN)
    assert load_grid(tmp_path / "bar.png").sum() == 5


def test_an_interrupted_save_leaves_the_old_file_intact(blank, tmp_path, monkeypatch):
    drag(blank, (8, 8), (12, 8))
    key(blank, pygame.K_s, pygame.KMOD_CTRL)
    before = (tmp_path / "drawn.png").read_bytes()
    drag(blank, (8, 12), (12, 12))

    def half_then_fail(self, fp, *args, **kwargs):
        with open(fp, "wb") as handle:
            handle.write(b"\\x89PNG half")
        raise OSError("disk full")

    monkeypatch.setattr(Image.Image, "save", half_then_fail)
    key(blank, pygame.K_s, pygame.KMOD_CTRL)
    assert "not saved" in blank.editor.message
    assert (tmp_path / "drawn.png").read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drawn.png"]


def test_quitting_with_unsaved_work_keeps_it(blank, tmp_path):
    drag(blank, (8, 8), (8, 12))
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    blank.tick()
    assert not blank.running
    kept = load_grid(tmp_path / "drawn.autosave.png")
    assert kept.shape == (5, 1) and kept.all()


def test_seeds_drag_and_turn_with_the_drawing(blank):
    drag(blank, (5, 5), (7, 5))
    seed = tuple(blank.editor.seeds[0])  # (2, 2) for the pose (3, 3)
    drag(blank, seed, (seed[0] + 10, seed[1] + 5))
    assert blank.editor.pose == Pose(13, 8)
    assert blank.editor.canvas.grid[15:18, 10].all() and blank.editor.canvas.grid.sum() == 3
    frame = blank.editor.shape().cells
    key(blank, pygame.K_t)
    assert blank.editor.pose.rotation == 90
    assert sorted(blank.editor.shape().cells.tolist()) == sorted(frame.tolist())
    drag(blank, tuple(blank.editor.seeds[0]), (0, 0))
    assert blank.editor.message and blank.editor.pose.x == 13  # refused, with a reason


def test_enter_starts_a_swarm_on_the_painted_shape(blank):
    key(blank, pygame.K_RETURN)
    assert blank.swarm is None and "paint" in blank.editor.message
    drag(blank, (10, 10), (15, 12), button=1)
    key(blank, pygame.K_RETURN)
    assert blank.swarm is not None and not blank.editing
    painted = {tuple(c) for c in blank.editor.canvas.cells.tolist()}
    assert {tuple(c) for c in blank.world.targets.tolist()} == painted
    for _ in range(200):
        blank.tick()
    assert blank.swarm.complete and blank.swarm.overlap_total == 0


def test_a_running_swarm_re_forms_live(tmp_path):
    view = Viewer(paper, world_of(np.ones((4, 6), dtype=bool), agents=32), title="box", fps=0)
    while not view.swarm.complete:
        view.tick()
    key(view, pygame.K_e)
    assert view.editing and view.swarm is not None
    corner = view.world.targets.max(axis=0)
    drag(view, (corner[0] + 1, corner[1] - 3), (corner[0] + 1, corner[1]))
    steps_before = view.swarm.step_count
    key(view, pygame.K_RETURN)
    assert not view.editing and len(view.world.targets) == 28
    assert view.swarm.step_count >= steps_before  # the same run goes on
    for _ in range(300):
        view.tick()
    assert view.swarm.complete and view.swarm.overlap_total == 0
    pygame.quit()


# --- nothing a user does loses their work -----------------------------------------------


def editor_on(path) -> Viewer:
    return Viewer(
        paper,
        blank_world((30, 20), Pose(3, 3), path.name, (200, 60, 60)),
        title=path.name,
        start=False,
        shape_file=path,
        size=(640, 480),
        fps=0,
    )


def type_text(view: Viewer, text: str) -> None:
    for letter in text:
        key(view, ord(letter), text=letter)


def clear_name(view: Viewer) -> None:
    for _ in range(len(view.editor.naming)):
        key(view, pygame.K_BACKSPACE)


@pytest.mark.parametrize("name", ["photo.jpg", "logo.png"])
def test_saving_never_replaces_an_image_that_is_not_a_drawing(tmp_path, name):
    original = tmp_path / name
    pixels = np.random.default_rng(1).integers(0, 255, (28, 32, 3), dtype=np.uint8)
    Image.fromarray(pixels).save(original)
    before = original.read_bytes()
    view = editor_on(original)
    assert "shape.png" in view.editor.message, "it says where Ctrl+S will save"
    drag(view, (8, 8), (12, 8))
    key(view, pygame.K_s, pygame.KMOD_CTRL)
    assert original.read_bytes() == before
    stem = original.stem
    assert view.editor.naming == f"{stem}.shape.png", "a fresh name is offered"
    key(view, pygame.K_RETURN)
    assert original.read_bytes() == before
    assert load_grid(tmp_path / f"{stem}.shape.png").sum() == 5
    drag(view, (8, 10), (8, 10))
    key(view, pygame.K_s, pygame.KMOD_CTRL)  # now the drawing's own file: saved at once
    assert view.editor.naming is None and load_grid(tmp_path / f"{stem}.shape.png").sum() == 6
    assert original.read_bytes() == before
    pygame.quit()


def test_the_offered_name_is_never_one_that_exists(tmp_path):
    original = tmp_path / "photo.jpg"
    Image.new("RGB", (8, 8), (0, 0, 0)).save(original)
    (tmp_path / "photo.shape.png").write_bytes(b"someone else's")
    view = editor_on(original)
    drag(view, (8, 8), (12, 8))
    key(view, pygame.K_s, pygame.KMOD_CTRL)
    assert view.editor.naming == "photo.shape-2.png"
    pygame.quit()


def test_saving_as_an_existing_name_asks_first(blank, tmp_path):
    other = tmp_path / "other.png"
    Image.new("RGB", (8, 8), (10, 200, 30)).save(other)
    before = other.read_bytes()
    drag(blank, (8, 8), (12, 8))
    for answer in (pygame.K_n, pygame.K_ESCAPE):
        key(blank, pygame.K_s, pygame.KMOD_CTRL | pygame.KMOD_SHIFT)
        clear_name(blank)
        type_text(blank, "other")
        key(blank, pygame.K_RETURN)
        question = blank._second_line()
        assert "replace" in question and "not a swarmshape drawing" in question
        assert other.read_bytes() == before
        key(blank, answer)
        assert other.read_bytes() == before and "not saved" in blank.editor.message
    key(blank, pygame.K_s, pygame.KMOD_CTRL | pygame.KMOD_SHIFT)
    clear_name(blank)
    type_text(blank, "other.png")
    key(blank, pygame.K_RETURN)
    key(blank, pygame.K_y, text="y")
    assert load_grid(other).sum() == 5 and blank.editor.path == other


def test_ctrl_s_asks_before_replacing_a_file_that_appeared_meanwhile(blank, tmp_path):
    drag(blank, (8, 8), (12, 8))
    (tmp_path / "drawn.png").write_bytes(b"written by something else")
    key(blank, pygame.K_s, pygame.KMOD_CTRL)
    assert (tmp_path / "drawn.png").read_bytes() == b"written by something else"
    assert "replace" in blank._second_line()
    key(blank, pygame.K_RETURN)
    assert load_grid(tmp_path / "drawn.png").sum() == 5


def test_autosave_never_overwrites_a_file(blank, tmp_path, capsys):
    (tmp_path / "drawn.autosave.png").write_bytes(b"not ours")
    drag(blank, (8, 8), (8, 12))
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    blank.tick()
    assert (tmp_path / "drawn.autosave.png").read_bytes() == b"not ours"
    kept = tmp_path / "drawn.autosave-2.png"
    assert load_grid(kept).sum() == 5
    assert str(kept) in capsys.readouterr().err


def quit_with_a_stroke(view: Viewer) -> None:
    drag(view, (8, 8), (8, 12))
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    view.tick()
    pygame.quit()


def test_autosave_falls_back_to_the_data_folder_then_the_temporary_one(
    tmp_path, monkeypatch, capsys, data_home
):
    spare = tmp_path / "tmp"
    spare.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(spare))
    quit_with_a_stroke(editor_on(tmp_path / "gone" / "drawn.png"))  # a folder not there
    assert load_grid(data_home / "swarmshape" / "autosaves" / "drawn.autosave.png").sum() == 5
    assert "kept in" in capsys.readouterr().err and not (tmp_path / "gone").exists()
    (data_home / "swarmshape").rename(data_home / "elsewhere")
    (data_home / "swarmshape").write_text("a file where the folder should be")
    quit_with_a_stroke(editor_on(tmp_path / "gone" / "drawn.png"))
    assert load_grid(spare / "drawn.autosave.png").sum() == 5


@pytest.mark.parametrize("where", ["shipped", "untitled"])
def test_autosave_of_a_shipped_shape_or_an_untitled_drawing_goes_to_the_data_folder(
    where, data_home, capsys
):
    """Never into the shapes that come with swarmshape (an update replaces them), nor into
    whatever folder the editor happened to be started from."""
    shipped = bundled_shapes() / "square.png"
    before = sorted(bundled_shapes().iterdir())
    view = Viewer(
        paper,
        world_of(np.ones((3, 3), dtype=bool)),
        title="square.png",
        start=False,
        shape_file=shipped if where == "shipped" else None,
        size=(640, 480),
        fps=0,
    )
    quit_with_a_stroke(view)
    name = "square.autosave.png" if where == "shipped" else "untitled.autosave.png"
    kept = data_home / "swarmshape" / "autosaves" / name
    assert kept.exists() and str(kept) in capsys.readouterr().err
    assert sorted(bundled_shapes().iterdir()) == before


def test_the_data_folder_follows_xdg_and_ignores_a_relative_setting(monkeypatch, tmp_path):
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    assert data_folder() == tmp_path / "swarmshape"
    monkeypatch.setenv("XDG_DATA_HOME", "relative/path")
    assert data_folder() == Path.home() / ".local" / "share" / "swarmshape"
    monkeypatch.delenv("XDG_DATA_HOME")
    assert data_folder() == Path.home() / ".local" / "share" / "swarmshape"
    monkeypatch.setattr(sys, "platform", "darwin")
    assert data_folder() == Path.home() / "Library" / "Application Support" / "swarmshape"
    monkeypatch.setattr(sys, "platform", "win32")
    monkeypatch.setenv("LOCALAPPDATA", str(tmp_path / "local"))
    assert data_folder() == tmp_path / "local" / "swarmshape"


# --- no surprises -----------------------------------------------------------------------


def colour_at(view: Viewer, cell: tuple[int, int]) -> tuple[int, int, int]:
    return tuple(view.screen.get_at(pixel(view, cell))[:3])


@pytest.mark.parametrize("code", [pygame.K_q, pygame.K_ESCAPE])
def test_q_and_esc_quit_the_editor_keeping_unsaved_work(blank, tmp_path, code, capsys):
    drag(blank, (8, 8), (8, 12))
    key(blank, code, text="q" if code == pygame.K_q else "")
    assert not blank.running
    assert load_grid(tmp_path / "drawn.autosave.png").sum() == 5
    assert "kept in" in capsys.readouterr().err


def test_while_typing_a_name_q_is_a_letter_and_esc_cancels_the_name(blank):
    drag(blank, (8, 8), (8, 12))
    key(blank, pygame.K_s, pygame.KMOD_CTRL | pygame.KMOD_SHIFT)
    clear_name(blank)
    key(blank, pygame.K_q, text="q")
    assert blank.running and blank.editor.naming == "q"
    key(blank, pygame.K_ESCAPE)
    assert blank.running and blank.editor.naming is None


def test_the_arena_follows_the_grid_size_at_once(blank):
    key(blank, pygame.K_PAGEUP)
    width, height = blank.editor.canvas.size
    assert width > 30 and f"grid {width}x{height}" in blank.status()
    corner = (width - 1, height - 1)  # a cell the old arena did not have
    drag(blank, corner, corner)
    assert blank.editor.canvas.grid[corner]
    assert colour_at(blank, corner) == PAINT


def test_shrinking_never_cuts_off_painted_cells_or_seeds(blank):
    drag(blank, (27, 10), (27, 10))
    key(blank, pygame.K_PAGEDOWN)
    assert blank.editor.canvas.size == (30, 20) and blank.editor.canvas.grid[27, 10]
    assert "cut off" in blank.editor.message
    drag(blank, (27, 10), (27, 10), button=3)
    seed = tuple(blank.editor.seeds[0])
    drag(blank, seed, (24, 16))  # seeds into the bottom-right corner
    key(blank, pygame.K_PAGEDOWN)
    assert blank.editor.canvas.size == (30, 20) and "seeds" in blank.editor.message
    drag(blank, (24, 16), (2, 2))
    key(blank, pygame.K_PAGEDOWN)
    assert blank.editor.canvas.size == (26, 17)


def test_the_arena_under_the_editor_shows_its_seeds_and_no_stale_shape(tmp_path):
    world = world_of(np.ones((3, 4), dtype=bool))
    view = Viewer(paper, world, title="box", start=False, size=(640, 480), fps=0)
    target = tuple(world.targets[0])
    drag(view, target, target, button=3)  # erased: no grey target left behind
    assert colour_at(view, target) == FLOOR
    seed = tuple(view.editor.seeds[0])
    moved = (seed[0] + 5, seed[1] + 3)
    drag(view, seed, moved)
    assert colour_at(view, seed) != SEED_GREEN, "no stale seed"
    assert colour_at(view, moved) == SEED_GREEN
    old = {tuple(c) for c in world.targets.tolist()}
    for cell in old - {tuple(c) for c in view.editor.canvas.cells.tolist()}:
        assert colour_at(view, cell) == FLOOR, "no ghost of the shape"
    pygame.quit()


def test_the_help_panel_covers_neither_the_seeds_nor_the_drawing(blank):
    drag(blank, (26, 15), (28, 18))
    key(blank, pygame.K_h)
    assert blank.editor.show_help
    for cell in blank.editor.seeds.tolist():
        assert colour_at(blank, tuple(cell)) == SEED_GREEN
    for cell in blank.editor.canvas.cells.tolist():
        assert colour_at(blank, tuple(cell)) == PAINT
    assert any("quit" in line for line in HELP_LINES)


def test_a_new_file_not_named_png_is_offered_a_png_name(tmp_path):
    view = editor_on(tmp_path / "new.jpg")
    assert "PNG" in view.editor.message
    drag(view, (8, 8), (12, 8))
    key(view, pygame.K_s, pygame.KMOD_CTRL)
    assert view.editor.naming == "new.png"
    key(view, pygame.K_RETURN)
    assert load_grid(tmp_path / "new.png").sum() == 5 and not (tmp_path / "new.jpg").exists()
    pygame.quit()


@pytest.mark.parametrize("flag", ["--save-state", "--record", "--trace"])
def test_an_output_that_names_the_drawing_is_refused_before_the_window_opens(
    tmp_path, capsys, monkeypatch, flag
):
    """A new drawing is no file yet, so no input to keep; but Ctrl+S writes it, and the
    output written at quit replaced it (a drawing became a state file, with no --force)."""
    from swarmshape.cli import main
    from swarmshape.ui import viewer

    def opened(*_, **__):
        raise AssertionError("the window opened")  # and would wait for a person for good

    monkeypatch.setattr(viewer, "Viewer", opened)

    drawing = tmp_path / "new.png"
    assert main(["edit", str(drawing), flag, str(tmp_path / "." / "new.png")]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.endswith(f"the editor's Ctrl+S and {flag} both write it; name two files")
    assert not drawing.exists()

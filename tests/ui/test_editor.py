"""The editor: canvas operations, and a person's clicks and keys posted as pygame events."""

from __future__ import annotations

import numpy as np
import pygame
import pytest
from PIL import Image

from swarmshape.core.shape import Pose
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import blank_world
from swarmshape.io.bitmap import load_grid
from swarmshape.strategies import create
from swarmshape.ui.editor import HISTORY, Canvas
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

from __future__ import annotations

import time

import numpy as np
import pygame
import pytest

from swarmshape.core.local import Program
from swarmshape.core.states import LOST
from swarmshape.core.swarm import Swarm
from swarmshape.experiments.trace import Trace
from swarmshape.runs import Observer, run
from swarmshape.strategies import create
from swarmshape.ui.render import legend
from swarmshape.ui.viewer import GAP, HUD_PAD, SPEEDS, Viewer
from tests.conftest import grid_from, make_swarm, world_of
from tests.ui.test_render import Shown

SHAPE = grid_from("""
####
""")


def window(plugin=lambda: create("paper"), **options) -> Viewer:
    """A window on `SHAPE`, run by a fresh `plugin` with seed 3."""
    return Viewer(
        lambda world: Swarm(world, plugin(), 3),
        world_of(SHAPE),
        title="bar.png",
        size=(640, 400),
        fps=0,
        **options,
    )


@pytest.fixture
def viewer(tmp_path):
    yield window(screenshots=tmp_path)
    pygame.quit()


def press(view: Viewer, key: int) -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, mod=0, unicode=""))
    view.tick()


def test_space_pauses_and_dot_steps_once(viewer):
    viewer.tick()
    press(viewer, pygame.K_SPACE)
    paused_at = viewer.swarm.step_count
    viewer.tick()
    assert viewer.swarm.step_count == paused_at
    press(viewer, pygame.K_PERIOD)
    assert viewer.swarm.step_count == paused_at + 1
    assert "PAUSED" in viewer.status()


def test_plus_and_minus_change_speed_within_bounds(viewer):
    start = viewer.speed
    press(viewer, pygame.K_PLUS)
    assert viewer.speed > start
    for _ in range(len(SPEEDS) + 2):
        press(viewer, pygame.K_MINUS)
    assert viewer.speed == SPEEDS[0]


def test_r_restarts_the_same_run(viewer):
    for _ in range(5):
        viewer.tick()
    first_cells = viewer.swarm.cell.copy()
    press(viewer, pygame.K_r)
    assert viewer.swarm.step_count <= viewer.speed
    assert viewer.swarm.seed == 3
    fresh = make_swarm(SHAPE, seed=3)
    for _ in range(viewer.swarm.step_count):
        fresh.step()
    assert (fresh.cell == viewer.swarm.cell).all()
    assert first_cells.shape == fresh.cell.shape


def test_f12_saves_a_png_of_the_window(viewer, tmp_path):
    viewer.tick()
    press(viewer, pygame.K_F12)
    shots = list(tmp_path.glob("swarmshape-*.png"))
    assert len(shots) == 1
    image = pygame.image.load(shots[0])
    assert image.get_size() == viewer.screen.get_size()


def test_f12_never_replaces_a_file_and_a_folder_it_cannot_write_is_a_notice(viewer, tmp_path):
    """The screenshot's name is the program's, not the user's: a file of that name stays, and a
    failure to write (a full disk, a folder without permission) is a line in the window, not the
    end of the run and of the outputs it was to write."""
    viewer.tick()
    viewer.paused = True
    taken = tmp_path / f"swarmshape-bar-{viewer.swarm.step_count}.png"
    taken.write_text("the user's notes")
    press(viewer, pygame.K_F12)
    assert taken.read_text() == "the user's notes"
    assert viewer.notice == f"saved {taken.with_name(taken.stem + '-2.png')}"
    viewer.screenshots = tmp_path / "no such folder"
    press(viewer, pygame.K_F12)
    assert viewer.notice.startswith("screenshot not saved: "), viewer.notice
    assert viewer.running


def resize(view: Viewer, size: tuple[int, int]) -> None:
    """What a person's drag of the window's edge does: SDL resizes the window (the dummy
    driver only does so through set_mode), then the window hears of it."""
    pygame.display.set_mode(size, pygame.RESIZABLE)
    pygame.event.post(pygame.event.Event(pygame.VIDEORESIZE, size=size, w=size[0], h=size[1]))
    view.tick()


def test_window_resizes_and_q_quits(viewer):
    resize(viewer, (500, 300))
    assert viewer.screen.get_size() == (500, 300)
    press(viewer, pygame.K_q)
    assert not viewer.running


# --- an idle window waits instead of burning CPU ----------------------------------------


def count_draws(view: Viewer, monkeypatch) -> list[int]:
    drawn = [0]
    draw = view.draw

    def counted() -> None:
        drawn[0] += 1
        draw()

    monkeypatch.setattr(view, "draw", counted)
    return drawn


def idle_ticks(view: Viewer, ticks: int = 3) -> tuple[int, float, float]:
    """Steps run, CPU seconds and wall seconds over a few ticks with no events."""
    steps, cpu, wall = view.swarm.step_count, time.process_time(), time.perf_counter()
    for _ in range(ticks):
        view.tick()
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    return view.swarm.step_count - steps, cpu, wall


def test_a_formed_swarm_with_nothing_moving_is_left_alone(viewer, monkeypatch):
    viewer.fps = 60
    while not viewer.swarm.complete:
        viewer.tick()
    viewer.tick()
    drawn = count_draws(viewer, monkeypatch)
    steps, cpu, wall = idle_ticks(viewer)
    assert steps == 0 and drawn[0] == 0
    assert wall > 0.3 and cpu < 0.5 * wall, "it waits for events, it does not spin"
    start = time.perf_counter()
    press(viewer, pygame.K_PLUS)  # a key still gets an answer at once
    assert time.perf_counter() - start < 0.2 and drawn[0] == 1
    assert viewer.swarm.step_count == viewer.swarm.completed_at[0], "no step once formed"


def test_a_paused_window_waits_for_events(viewer, monkeypatch):
    viewer.fps = 60
    viewer.tick()
    press(viewer, pygame.K_SPACE)
    drawn = count_draws(viewer, monkeypatch)
    steps, cpu, wall = idle_ticks(viewer)
    assert steps == 0 and drawn[0] == 0
    assert wall > 0.3 and cpu < 0.5 * wall
    press(viewer, pygame.K_SPACE)
    assert drawn[0] == 1 and viewer.swarm.step_count > 1


def test_the_window_stops_at_max_steps_and_keeps_the_final_swarm(tmp_path):
    view = window(max_steps=5)
    assert "step 0/5" in view.status()
    for _ in range(4):
        view.tick()
    assert view.swarm.step_count == 5 and not view.swarm.complete
    assert "step 5/5" in view.status() and "max steps" in view.status()
    press(view, pygame.K_PERIOD)
    assert view.swarm.step_count == 5 and "max-steps" in view.notice
    final = view.swarm
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    view.run()
    assert view.swarm is final and view.swarm.step_count == 5


def test_no_step_runs_after_the_user_quit(viewer):
    viewer.tick()
    before = viewer.swarm.step_count
    press(viewer, pygame.K_q)
    assert not viewer.running and viewer.swarm.step_count == before


def click(view: Viewer, kind: int, pixel: tuple[int, int]) -> None:
    if kind == pygame.MOUSEMOTION:
        event = pygame.event.Event(kind, pos=pixel, rel=(0, 0), buttons=(1, 0, 0))
    else:
        event = pygame.event.Event(kind, pos=pixel, button=1)
    pygame.event.post(event)
    view.tick()


def formed_under_optimal(shape: np.ndarray, agents: int, folder) -> Viewer:
    """A window whose swarm has formed `shape` with `agents` robots, under `optimal`."""
    view = Viewer(
        lambda world: Swarm(world, create("optimal"), 3),
        world_of(shape, agents),
        title="block.png",
        size=(640, 400),
        fps=0,
        screenshots=folder,
    )
    while not view.swarm.complete:
        view.tick()
    return view


def test_the_fault_tool_removes_a_clicked_robot_and_a_dragged_rectangle(tmp_path):
    block = grid_from("""
    ########
    ########
    ########
    ########
    """)
    view = formed_under_optimal(block, 40, tmp_path)
    try:
        press(view, pygame.K_SPACE)
        press(view, pygame.K_x)
        assert view.fault_tool and "FAULT TOOL" in view.status()
        area = view._world_area()
        target = tuple(view.swarm.world.targets[0].tolist())
        pixel = view.renderer.cell_rect(target, area).center
        robot = int(np.flatnonzero((view.swarm.cell == target).all(axis=1))[0])
        click(view, pygame.MOUSEBUTTONDOWN, pixel)
        click(view, pygame.MOUSEBUTTONUP, pixel)
        assert view.swarm.state[robot] == LOST and view.notice == "removed 1 robot"
        corner = view.swarm.world.targets.min(axis=0) + np.array([3, 1])
        far = corner + np.array([2, 1])
        click(view, pygame.MOUSEBUTTONDOWN, view.renderer.cell_rect(tuple(corner), area).center)
        click(view, pygame.MOUSEMOTION, view.renderer.cell_rect(tuple(far), area).center)
        assert view._drag_from is not None
        click(view, pygame.MOUSEBUTTONUP, view.renderer.cell_rect(tuple(far), area).center)
        assert view.notice == "removed 6 robots" and view.swarm.faults.lost == 7
        assert [f["kind"] for f in view.swarm.faults.log] == ["window", "window"]
        shot = view.screenshot()  # the red marks where they were
        image = pygame.surfarray.array3d(pygame.image.load(shot))
        assert ((image == (214, 40, 40)).all(axis=2)).sum() > 20
        press(view, pygame.K_x)
        press(view, pygame.K_SPACE)
        while not view.swarm.complete:
            view.tick()
        assert view.swarm.overlap_total == 0 and view.swarm.filled.all()
    finally:
        pygame.quit()


def test_g_l_o_toggle_a_local_programs_overlays_and_say_so(viewer, tmp_path):
    press(viewer, pygame.K_g)  # the fixture runs the central `paper` strategy
    assert viewer.overlays == set() and "no local program" in viewer.notice
    view = window(Shown, screenshots=tmp_path)
    try:
        for key in (pygame.K_g, pygame.K_l, pygame.K_o):
            press(view, key)
        assert view.overlays == {"values", "links", "error"}
        assert "showing error links values" in view.status()
        press(view, pygame.K_l)
        assert view.overlays == {"values", "error"} and view.notice == "links overlay off"
    finally:
        pygame.quit()


# --- the window drives a runs.Runner -----------------------------------------------------


def test_the_window_feeds_its_observers_as_a_headless_run_does(tmp_path):
    """The same observers see the same steps, from the swarm before its first step to the
    formed shape, and are closed when the window closes."""
    view = window(observers=[Trace(tmp_path / "window.csv")])
    while not view.idle:
        view.tick()
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    view.run()
    run(Swarm(world_of(SHAPE), create("paper"), 3), [Trace(tmp_path / "headless.csv")])
    shown = (tmp_path / "window.csv").read_text()
    assert shown == (tmp_path / "headless.csv").read_text()
    assert shown.splitlines()[1].startswith("0,"), "the swarm before its first step"


def test_a_window_that_fails_discards_its_observers_half_written_files(tmp_path):
    class Breaks(Observer):
        discarded = False

        def capture(self, swarm: Swarm) -> None:
            if swarm.step_count == 3:
                raise RuntimeError("disk on fire")

        def discard(self) -> None:
            self.discarded = True

    breaks = Breaks()
    view = window(observers=[breaks])
    with pytest.raises(RuntimeError, match="disk on fire"):
        view.run()
    assert breaks.discarded


class Still(Program):
    """Robots that never move and always say the same: a program that goes quiet."""

    name = "still"
    message_size = 1

    def act(self, sense, memory, rng):
        return np.zeros(len(sense), dtype=np.int64), np.zeros((len(sense), 1), dtype=np.int64)


def test_a_local_program_gone_quiet_leaves_the_window_idle_where_a_headless_run_stops():
    view = window(Still)
    try:
        for _ in range(200):
            if view.idle:
                break
            view.tick()
        headless = run(Swarm(world_of(SHAPE), Still(), 3))
        assert view.idle and view.swarm.step_count == headless.step_count
        assert not view.swarm.complete
    finally:
        pygame.quit()


# --- a HUD that explains itself ----------------------------------------------------------


def test_the_pace_reads_right_for_one_step_many_and_fractions(viewer):
    for speed, words in ((1, "1 step/frame"), (8, "8 steps/frame"), (0.125, "1 step/8 frames")):
        viewer.speed_index = SPEEDS.index(speed)
        assert f"   {words}   " in viewer.status()


def test_an_idle_window_says_why_where_the_frame_rate_stood(viewer):
    viewer.tick()
    assert "FPS" in viewer.status() and "idle" not in viewer.status()
    press(viewer, pygame.K_SPACE)
    assert "idle: PAUSED, Space goes on" in viewer.status() and "FPS" not in viewer.status()
    press(viewer, pygame.K_SPACE)
    while not viewer.idle:
        viewer.tick()
    assert "idle: formed, nothing moves" in viewer.status()


def test_a_formed_shape_short_of_a_robot_says_how_many_cells_stay_open(viewer):
    while not viewer.idle:
        viewer.tick()
    viewer.swarm.fail(np.array([0]))  # no spares: the shape keeps its size, with a hole
    while not viewer.idle:
        viewer.tick()
    assert len(viewer.swarm.filled) == 4
    assert "idle: formed as far as the robots go, 1 cell open" in viewer.status()


def test_a_notice_leaves_the_key_help_in_view(viewer):
    viewer.tick()
    press(viewer, pygame.K_r)
    top, _, helps, _ = viewer._layout()
    assert viewer._second_line() == "restarted with seed 3"
    assert "restarted with seed 3" in [text for text, _ in top]
    assert "r restart" in " ".join(helps) and "q quit" in " ".join(helps)


def test_with_nothing_to_tell_the_second_line_says_what_runs(viewer):
    viewer.tick()
    assert viewer._second_line() == "bar.png: paper, 4 robots for 4 cells"


@pytest.mark.parametrize("size", [(320, 240), (640, 400), (1280, 800), (2560, 1440)])
def test_the_hud_fits_the_window_at_every_size(viewer, size):
    """Every line of the bars fits the width (a single word too wide for it excepted), the
    legend too (where it leaves the arena at least half the height), and the arena keeps
    nearly half the window even when it is tiny."""
    press(viewer, pygame.K_x)  # a long notice
    resize(viewer, size)
    top, keys, helps, area = viewer._layout()
    room = size[0] - 2 * HUD_PAD
    for text in [text for text, _ in top] + helps:
        assert viewer.font.size(text)[0] <= room or " " not in text, text
    for row in keys:
        gaps = (len(row) - 1) * viewer.font.size(GAP)[0]
        assert sum(viewer._key_width(key) for key in row) + gaps <= room
    shown = sum(len(row) for row in keys)
    assert shown == (len(legend(viewer.swarm)) if size[1] >= 400 else 0)
    assert area.height >= 0.45 * size[1]


def test_a_live_edit_the_robots_left_cannot_fill_is_refused_in_the_editor(tmp_path):
    """Issue 29, cases 6 and 17: after a fault, handing over the shape the run began with went
    ahead with more cells than robots; it never formed, and the metrics raised at quit."""
    view = formed_under_optimal(grid_from("####\n####"), 8, tmp_path)
    try:
        first = view.swarm.world.targets.copy()
        view.swarm.fail(np.arange(3))
        view.start_editing()
        view.editor.canvas.grid[first[:, 0], first[:, 1]] = True  # the first 8 cells again
        view.finish_editing()
        assert view.editing and "for the 5 robots that can move: short by 3" in view.editor.message
        # the shape kept its size through the fault (on_loss keep), and the refused edit
        # changed nothing
        assert np.array_equal(view.swarm.world.targets, first)
    finally:
        pygame.quit()

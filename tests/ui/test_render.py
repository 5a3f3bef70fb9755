from __future__ import annotations

from typing import ClassVar

import numpy as np
import pygame
import pytest

from swarmshape.core.local import Program, Slot
from swarmshape.core.shape import Pose, Shape
from swarmshape.core.states import State
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.strategies import create
from swarmshape.ui.render import (
    BORDER_MIN_SIDE,
    ERROR_RED,
    FLOOR,
    PALETTE,
    SEED_GREEN,
    TARGET,
    TEXT_DARK,
    Renderer,
    legend,
    shown_of,
    square_of,
)
from tests.conftest import grid_from, make_swarm

SHAPE = grid_from("""
###
#..
""")


def centre_of(rect: pygame.Rect) -> tuple[int, int]:
    return rect.centerx, rect.centery


def test_a_frame_shows_seeds_green_targets_grey_and_agents_in_their_colour():
    swarm = make_swarm(SHAPE, seed=1)
    surface = pygame.Surface((400, 300))
    renderer = Renderer(swarm.world)
    renderer.draw(surface, swarm)
    seed = renderer.cell_rect(tuple(swarm.world.seeds[0]), surface.get_rect())
    target = renderer.cell_rect(tuple(swarm.world.targets[0]), surface.get_rect())
    assert surface.get_at(centre_of(seed))[:3] == SEED_GREEN
    assert surface.get_at(centre_of(target))[:3] == TARGET
    assert surface.get_at(seed.topleft)[:3] == FLOOR  # a one-pixel gap shows the grid
    waiting = int((swarm.state == State.WAITING).nonzero()[0][0])
    agent = renderer.cell_rect(tuple(swarm.cell[waiting]), surface.get_rect())
    colour = surface.get_at(centre_of(agent))[:3]
    assert colour not in (FLOOR, TARGET, SEED_GREEN)
    assert colour[0] > colour[2], "the group's colour (red here), pale while waiting"


def test_the_world_scales_to_fit_any_area():
    swarm = make_swarm(SHAPE, seed=1)
    renderer = Renderer(swarm.world)
    width, height = swarm.world.size
    for size in ((200, 100), (1280, 800), (300, 900)):
        cell, (ox, oy) = renderer.fit(pygame.Rect((0, 0), size))
        assert cell * width <= size[0] and cell * height <= size[1]
        assert (cell + 1) * width > size[0] or (cell + 1) * height > size[1]
        assert ox >= 0 and oy >= 0


class Shown(Program):
    """Robots stay put, take state ``number % 3``, keep their number as a gradient to show, and
    believe they are all on the shape's first cell."""

    name = "shown"
    description = "test: states, a shown slot and an estimate"
    message_size = 1
    memory: ClassVar[dict[str, Slot]] = {"state": Slot(np.int64), "hops": Slot(np.int64, 999)}
    states = ("first", "second", "third")
    shown = "hops"

    def act(self, sense, memory, rng):
        memory.state = sense.number % 3
        memory.hops = sense.number
        return np.zeros(len(sense), dtype=np.int64), memory.hops[:, None].copy()

    def estimate(self, memory):
        return np.ones(len(memory), dtype=bool), np.zeros((len(memory), 2), dtype=np.int64)


def local_swarm() -> Swarm:
    """Three robots two cells apart in a row, below a 1 x 3 shape whose first cell is (2, 2)."""
    world = build_world(
        [GroupSpec("g", Shape(np.ones((1, 3), dtype=bool)), (200, 60, 60), 3, Pose(2, 2))],
        (12, 8),
    )
    swarm = Swarm(world, Shown(), seed=1, start=np.array([[2, 5], [4, 5], [6, 5]]))
    swarm.step()
    return swarm


def drawn(swarm: Swarm, overlays=()) -> tuple[pygame.Surface, Renderer]:
    surface = pygame.Surface((480, 320))
    renderer = Renderer(swarm.world)
    renderer.draw(surface, swarm, None, overlays)
    return surface, renderer


def test_a_local_program_with_states_colours_its_robots_by_state():
    swarm = local_swarm()
    surface, renderer = drawn(swarm)
    assert shown_of(swarm).plugin == "shown" and shown_of(make_swarm(SHAPE)) is None
    names = [key.name for key in legend(swarm)]
    assert names == ["first", "second", "third", "stalled", "removed", "seed", "empty cell"]
    for robot in range(3):
        rect = renderer.cell_rect(tuple(swarm.cell[robot]), surface.get_rect())
        assert surface.get_at(rect.move(3, 3).topleft)[:3] == PALETTE[robot % 3]


def test_overlays_draw_values_links_and_localisation_error_only_when_asked():
    swarm = local_swarm()
    plain, renderer = drawn(swarm)
    area = plain.get_rect()
    robot = renderer.cell_rect(tuple(swarm.cell[1]), area)  # its value is 1
    between = renderer.cell_rect((3, 5), area).center  # floor between robots 0 and 1

    def dark_pixels(surface: pygame.Surface) -> int:
        pixels = pygame.surfarray.array3d(surface.subsurface(robot))
        return int((np.abs(pixels - np.array(TEXT_DARK)).sum(axis=2) < 60).sum())

    values, _ = drawn(swarm, {"values"})
    assert dark_pixels(plain) == 0 and dark_pixels(values) > 5
    links, _ = drawn(swarm, {"links"})
    assert plain.get_at(between)[:3] == FLOOR
    red, green, blue = links.get_at(between)[:3]
    assert blue > red and (red, green, blue) != FLOOR, "a link crosses the gap"
    error, _ = drawn(swarm, {"error"})
    believed = renderer.cell_rect((2, 2), area).center  # the shape's first cell
    assert error.get_at(believed)[:3] == ERROR_RED
    assert plain.get_at(believed)[:3] != ERROR_RED


def test_overlays_ask_nothing_of_a_central_strategy():
    swarm = make_swarm(SHAPE, seed=1)
    plain, _ = drawn(swarm)
    everything, _ = drawn(swarm, {"values", "links", "error"})
    assert pygame.image.tobytes(plain, "RGB") == pygame.image.tobytes(everything, "RGB")


@pytest.mark.parametrize("strategy", ["optimal", "paper", "local-swap", "self-assembly"])
def test_every_colour_on_the_arena_has_a_key_in_the_legend(strategy):
    """Seeds, empty cells and every robot's colour, whatever it is doing (spares wander, one is
    stalled, one removed), under central strategies and local programs alike."""
    world = build_world([GroupSpec("g", Shape(np.ones((3, 4), dtype=bool)), (200, 60, 60), 16)])
    swarm = Swarm(world, create(strategy), seed=2)
    for _ in range(12):
        swarm.step()
    swarm.fail(np.array([0]), "stall")
    swarm.fail(np.array([1]), "remove")
    surface, renderer = drawn(swarm)
    keys = legend(swarm)
    swatches = {colour for key in keys for colour in (*key.colours, *key.borders)}
    size, origin = renderer.fit(surface.get_rect())
    empty = ~swarm.filled & ~(swarm.cell[swarm.present][:, None] == world.targets).all(2).any(0)
    # a robot's colour at its square's corner (a border, for a spare one), the others' centres
    corners = swarm.positions()[swarm.present] - 0.5 + 1 / size
    centres = [*corners, *(world.seeds + 0.5), *(world.targets[empty] + 0.5)]
    for centre in centres:
        pixel = (np.floor(centre * size) + origin).astype(int)
        assert surface.get_at(pixel.tolist())[:3] in swatches, (strategy, centre)
    assert {"stalled", "removed", "seed", "empty cell"} <= {key.name for key in keys}
    if not shown_of(swarm) or not shown_of(swarm).states:
        assert [key.name for key in keys][:4] == ["waiting", "moving", "settled", "wandering"]


def test_a_spare_robot_has_a_border_of_its_colour_and_the_legend_says_so():
    """Waiting and wandering were two pale shades of one colour, hard to tell apart; a robot
    with nothing to do now has a border of its group's full colour round its paler shade, and
    where squares are too small for a border, that shade still tells it from a moving one."""
    world = build_world([GroupSpec("g", Shape(np.ones((2, 2), dtype=bool)), (200, 60, 60), 9)])
    swarm = Swarm(world, create("optimal"), seed=2)
    while not swarm.complete:
        swarm.step()
    spare = int(np.flatnonzero(swarm.state == State.WANDERING)[0])
    surface, renderer = drawn(swarm)
    square = renderer.cell_rect(tuple(swarm.cell[spare]), surface.get_rect()).inflate(-2, -2)
    keys = {key.name: key for key in legend(swarm)}
    wandering, waiting = keys["wandering"], keys["waiting"]
    assert surface.get_at(square.topleft)[:3] == (200, 60, 60) == wandering.borders[0]
    assert surface.get_at(centre_of(square))[:3] == wandering.colours[0]
    assert wandering.colours[0] not in (waiting.colours[0], keys["moving"].colours[0], FLOOR)
    assert not waiting.borders
    tiny = square_of(BORDER_MIN_SIDE - 1, wandering.colours[0], wandering.borders[0])
    assert {tiny.get_at((x, y))[:3] for x in range(3) for y in range(3)} == {wandering.colours[0]}

from __future__ import annotations

import pygame

from swarmshape.core.states import State
from swarmshape.ui.render import FLOOR, SEED_GREEN, TARGET, Renderer
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

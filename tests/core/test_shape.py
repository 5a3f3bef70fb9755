from __future__ import annotations

import numpy as np
import pytest

from swarmshape.core.shape import SEED_CELLS, Pose, Shape, ShapeError
from swarmshape.core.world import GroupSpec, WorldError, build_world, cells_at
from tests.conftest import grid_from

L_SHAPE = grid_from("""
#..
#..
###
""")


def test_pose_moves_cells_and_turns_them_a_quarter_clockwise():
    cells = np.array([[0, 0], [2, 0], [0, 1]])
    assert Pose(5, 7).to_world(cells).tolist() == [[5, 7], [7, 7], [5, 8]]
    # a quarter turn clockwise on screen (y down): +x goes to +y, +y goes to -x
    assert Pose(0, 0, 90).to_world(cells).tolist() == [[-1, 0], [-1, 2], [-2, 0]]
    assert Pose(0, 0, 360).to_world(cells).tolist() == cells.tolist()


def test_rotation_must_be_a_quarter_turn():
    with pytest.raises(ShapeError, match="multiple of 90"):
        Pose(0, 0, 45)


def test_seeds_are_at_least_three_and_not_collinear():
    assert len(SEED_CELLS) >= 3
    assert np.linalg.matrix_rank(SEED_CELLS[1:] - SEED_CELLS[0]) == 2


def test_rotating_the_seed_pose_rotates_the_formed_shape():
    plain = build_world([GroupSpec("g", Shape(L_SHAPE), (1, 2, 3), pose=Pose(10, 10))], (30, 30))
    turned = build_world(
        [GroupSpec("g", Shape(L_SHAPE), (1, 2, 3), pose=Pose(10, 10, 180))], (30, 30)
    )
    centre = np.array([10, 10])
    # a half turn about the frame origin maps cell c to -c - 1
    expected = {tuple(c) for c in (2 * centre - plain.targets - 1).tolist()}
    assert {tuple(c) for c in turned.targets.tolist()} == expected
    assert {tuple(c) for c in (2 * centre - plain.seeds - 1).tolist()} == {
        tuple(c) for c in turned.seeds.tolist()
    }


def test_fitting_to_fewer_agents_picks_the_largest_scale_that_fits():
    square = Shape(np.ones((10, 10), dtype=bool))
    fitted = square.fitted(30)
    assert fitted.count <= 30
    assert fitted.scale == pytest.approx(0.5)  # 5x5 = 25 fits, 6x6 = 36 does not
    assert square.fitted(100) is square


def test_world_places_targets_away_from_the_border_and_checks_room():
    world = build_world([GroupSpec("g", Shape(L_SHAPE), (1, 2, 3))])
    assert world.targets.min() >= 3
    assert (world.targets < np.array(world.size) - 3).all()
    assert len(world.start_cells()) >= world.agents
    with pytest.raises(WorldError, match="no room"):
        build_world([GroupSpec("g", Shape(L_SHAPE), (1, 2, 3), 5, Pose(1, 1))], (5, 5))


def test_groups_may_not_overlap():
    specs = [GroupSpec(n, Shape(L_SHAPE), (1, 2, 3), pose=Pose(5, 5)) for n in "ab"]
    with pytest.raises(WorldError, match="overlap"):
        build_world(specs, (30, 30))


def test_to_frame_undoes_to_world_for_every_rotation():
    cells = np.array([[0, 0], [3, -2], [-1, 5]])
    for rotation in (0, 90, 180, 270):
        pose = Pose(7, -3, rotation)
        assert pose.to_frame(pose.to_world(cells)).tolist() == cells.tolist()


def test_a_shape_from_cells_keeps_where_they_are():
    cells = np.array([[-2, 1], [-1, 1], [0, 3]])
    shape = Shape.from_cells(cells)
    assert shape.origin == (-2, 1) and shape.grid.shape == (3, 3)
    assert sorted(shape.cells.tolist()) == sorted(cells.tolist())


def test_a_seeded_shape_touches_its_seeds_and_one_that_already_did_stays_put():
    star_tip = Shape(grid_from("..#.. .###. #####"))
    assert star_tip.origin == (0, 0)  # central strategies keep the corner placement
    assert star_tip.seeded().origin == (-2, 0)
    assert [0, 0] in star_tip.seeded().cells.tolist()
    under_the_arm = Shape(grid_from(".## ###"))
    assert under_the_arm.seeded() is under_the_arm
    painted = Shape(grid_from("#"), origin=(5, 5))
    assert painted.seeded().cells.tolist() == [[0, 0]]


def test_the_solid_part_fills_what_the_seeds_enclose_and_drops_what_they_cannot_reach():
    # a notch under the seeds' arm becomes a hole once the row below is built
    notched = Shape(grid_from("#.# ###"))
    assert not notched.is_solid
    assert sorted(notched.solid().cells.tolist()) == sorted(
        [[x, y] for x in range(3) for y in range(2)]
    )
    apart = Shape(grid_from("##... ##..# ....#"))
    assert sorted(apart.solid().cells.tolist()) == [[0, 0], [0, 1], [1, 0], [1, 1]]
    ring = Shape(grid_from("### #.# ###"))
    assert ring.solid().count == 9
    assert Shape(grid_from("### #.. ###")).is_solid
    assert not Shape(grid_from(".#. ###")).is_solid  # the seed L's corner becomes a hole
    assert not Shape(grid_from("..# ###")).is_solid  # apart from the seeds until seeded
    assert Shape(grid_from("..# ###")).seeded().is_solid


FUZZED_SEALED = """
..#..#..#
.#######.
#.#######
#....##..
###.#.#.#
##.#.####
##.###..#
"""


def test_cells_of_pieces_that_only_pockets_touch_are_found():
    ring_with_a_dot = Shape(grid_from("##### #...# #.#.# #...# #####"))
    assert ring_with_a_dot.sealed().tolist() == [[2, 2]]
    assert len(Shape(grid_from("####### #.....# #.###.# #.....# #######")).sealed()) == 3
    assert len(Shape(grid_from("##.## ##.##")).sealed()) == 0  # apart, both on the outside
    assert len(Shape(grid_from("### #.# ###")).sealed()) == 0  # a pocket, but nothing in it
    # drawn at random (a fuzz): a one-cell piece in a pocket that two other pieces wall in
    assert len(Shape(grid_from(FUZZED_SEALED)).sealed()) == 1


def test_a_sealed_piece_within_the_radius_of_a_piece_reached_is_reached():
    """Two cells from the ring, the dot is in reach of a robot on the ring that senses two
    cells; a dot in a ring's middle three cells from it is not, until the radius reaches it,
    and a piece within reach of a piece so reached is reached too."""
    ring_with_a_dot = Shape(grid_from("##### #...# #.#.# #...# #####"))
    assert len(ring_with_a_dot.sealed(1.9)) == 1 and len(ring_with_a_dot.sealed(2.0)) == 0
    wide = Shape(grid_from("####### #.....# #.....# #..#..# #.....# #.....# #######"))
    assert len(wide.sealed(2.0)) == 1 and len(wide.sealed(3.0)) == 0
    nested = Shape(
        grid_from("######### #.......# #.#####.# #.#...#.# #.#.#.#.# #.#...#.# #.#####.# "
                  "#.......# #########")
    )  # fmt: skip
    assert len(nested.sealed()) == 17
    assert len(nested.sealed(1.9)) == 17 and len(nested.sealed(2.0)) == 0


def test_a_solid_shape_stays_solid_when_fitted_to_fewer_robots():
    shape = Shape(grid_from("..#... .#..#. .#..#. ###### ###...")).seeded()
    assert shape.is_solid  # its two tips touch the seeds
    for agents in range(1, shape.count):  # shrunk to 5 cells across, a plain resample is not
        fitted = shape.fitted(agents)
        assert fitted.is_solid and fitted.count <= agents


@pytest.mark.parametrize("x", [10**20, -(10**20), 2**63, 25_000_001])
def test_a_pose_beyond_any_arena_is_refused(x):
    """Issue 29, case 12: a scenario pose beyond int64 made object arrays, was accepted, and
    the automatic arena then shifted it away (ignored without a word)."""
    with pytest.raises(ShapeError, match="lies beyond any arena"):
        Pose(x, 0)
    with pytest.raises(ShapeError, match="lies beyond any arena"):
        Pose(0, x, 90)
    assert Pose(25_000_000, -25_000_000).x == 25_000_000


def test_a_shape_without_cells_is_refused_wherever_a_world_is_made():
    """Issue 29, case 12: an all-empty grid with agents=1 built a world, and the first step
    (vector_env's reset) raised an IndexError."""
    empty = Shape(np.zeros((3, 3), dtype=bool))
    with pytest.raises(WorldError, match="group 'g': its shape has no cells"):
        build_world([GroupSpec("g", empty, (1, 2, 3), 1)])
    world = build_world([GroupSpec("g", Shape(grid_from("##")), (1, 2, 3))])
    with pytest.raises(WorldError, match="its shape has no cells"):
        world.reshaped(0, empty, world.groups[0].pose)


def test_a_world_and_its_shapes_are_read_only():
    """Issue 29, case 15: a strategy wrote `swarm.targets[0] = ...` and
    `swarm.world.seeds[:] = 0` through its SwarmView, and the run reported 1,800 overlaps; the
    README says the view is read-only. The world's arrays are read-only where they are made."""
    grid = grid_from("##\n#.")
    world = build_world([GroupSpec("g", Shape(grid), (1, 2, 3))])
    group = world.groups[0]
    arrays = [world.targets, world.target_group, world.seeds, group.targets, group.seeds,
              group.frame_cells, group.shape.grid]  # fmt: skip
    for array in arrays:
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1
    grid[0, 1] = False  # the shape kept its own copy
    assert group.shape.grid[0, 1]


def test_each_groups_targets_lie_together_where_targets_of_says():
    """The swarm checks a group's targets by the span `targets_of` gives, not by a mask over
    every target: each group's targets, and only they, lie there."""
    shapes = [Shape(grid_from("###\n#.#")), Shape(grid_from("#")), Shape(grid_from("##\n##"))]
    world = build_world([GroupSpec(f"g{k}", shape, (1, 2, 3)) for k, shape in enumerate(shapes)])
    for group in range(3):
        span = np.arange(len(world.targets))[world.targets_of(group)]
        assert span.tolist() == np.flatnonzero(world.target_group == group).tolist()
        assert len(span) == len(world.groups[group].targets) > 0


def test_fitting_a_wide_shape_to_few_robots_resamples_it_a_few_times_not_once_per_side(
    monkeypatch,
):
    """Issue 29, case 8: --cells 2000 --agents 5 took 3 minutes (--cells 3000 over 15): the
    fit resampled the whole grid once for every side from 1,999 down. Its cost is now a few
    dozen resamplings, and it finds the copy the side-by-side search found."""
    from swarmshape.core import shape as module

    calls = []
    real = module.resample

    def counted(fraction, side):
        calls.append(side)
        return real(fraction, side)

    monkeypatch.setattr(module, "resample", counted)
    yy, xx = np.mgrid[:100, :200]
    wide = Shape(((xx - 100) / 100) ** 2 + ((yy - 50) / 50) ** 2 <= 1)  # an ellipse
    for agents in (5, 700, wide.count - 1):
        calls.clear()
        fitted = wide.fitted(agents)
        assert len(calls) <= 30, len(calls)
        assert 0 < fitted.count <= agents
        bigger = next(s for s in (wide._copy(side, False) for side in range(199, 0, -1))
                      if s.count <= agents)  # fmt: skip
        assert (fitted.count, fitted.scale) == (bigger.count, bigger.scale)


def test_start_cells_picked_by_place_are_those_of_the_whole_list():
    world = build_world([GroupSpec("g", Shape(grid_from("###\n#.#")), (1, 2, 3), 40)])
    every = world.start_cells()
    rng = np.random.default_rng(3)
    chosen = rng.choice(len(every), 25, replace=False)
    assert np.array_equal(cells_at(world.start_mask(), chosen), every[chosen])
    assert np.array_equal(cells_at(world.start_mask(), np.arange(len(every))), every)

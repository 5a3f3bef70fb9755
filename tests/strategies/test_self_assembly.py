"""`self-assembly` (Rubenstein, Cornejo & Nagpal 2014 on the lattice) forms small hole-free
shapes from a packed block and from a scattered start, deterministically, without overlaps,
and its joined robots never move again."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from swarmshape.config import RunConfig, configure
from swarmshape.core.faults import FaultEvent, Faults
from swarmshape.core.metrics import run_metrics
from swarmshape.core.shape import Shape
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.errors import InputError
from swarmshape.io.bitmap import ShapeWarning
from swarmshape.runs import Runner, build, run
from swarmshape.strategies import create
from swarmshape.strategies.self_assembly import (
    INSIDE,
    JOINED,
    OUTSIDE,
    STOPPED,
    WAIT,
    WANDER,
    SelfAssembly,
)
from tests.conftest import SHAPES, each_choice, grid_from


def formed(shape: str, **options):
    config = configure(SHAPES / shape, strategy="self-assembly", **options)
    return run(build(config), max_steps=20_000)


@pytest.mark.parametrize(
    ("shape", "cells", "start"),
    each_choice(
        (*shape, start)
        for shape in [("small-square.png", None), ("horseshoe.png", None), ("letter-k.png", 12)]
        for start in ["packed", "scatter"]
    ),
)
def test_small_hole_free_shapes_form_without_overlaps(shape, cells, start):
    swarm = formed(shape, cells=cells, start=start, seed=2)
    metrics = run_metrics(swarm)
    assert metrics["coverage"] == 1.0 or metrics["iou"] >= 0.9, metrics
    assert swarm.overlap_total == 0


def test_the_same_seed_gives_the_same_run():
    a, b = (formed("horseshoe.png", start="packed", seed=7) for _ in "ab")
    assert a.step_count == b.step_count
    assert np.array_equal(a.cell, b.cell)
    assert np.array_equal(a.driver.memory.state, b.driver.memory.state)


def test_with_lost_messages_and_noisy_distances_the_shape_still_forms():
    swarm = formed("small-square.png", start="packed", seed=3, msg_loss=0.1, distance_noise=0.1)
    assert run_metrics(swarm)["iou"] >= 0.9
    assert swarm.overlap_total == 0


def test_the_packed_block_counts_its_hops_from_the_seeds_in_the_shown_gradient():
    """Rubenstein's gradient through touching (8-neighbour) robots: in the block packed against
    the seed L it is each waiting robot's chessboard distance to the nearest seed."""
    swarm = build(configure(SHAPES / "letter-k.png", strategy="self-assembly", start="packed",
                            cells=12, seed=1))  # fmt: skip
    for _ in range(200):
        swarm.step()
    memory = swarm.driver.memory
    waiting = memory.state == WAIT
    apart = np.abs(swarm.cell[waiting][:, None, :] - swarm.world.seeds[None]).max(axis=2)
    assert waiting.sum() > 20
    assert np.array_equal(getattr(memory, SelfAssembly.shown)[waiting], apart.min(axis=1))


def test_joined_robots_never_move_again():
    config = configure(SHAPES / "horseshoe.png", strategy="self-assembly", start="packed", seed=4)
    runner = Runner(build(config), max_steps=20_000)
    swarm = runner.swarm
    joined, where = np.zeros(len(swarm.cell), dtype=bool), swarm.cell.copy()
    while not runner.finished:
        runner.step()
        assert (swarm.cell[joined] == where[joined]).all()
        joined = swarm.driver.memory.state == JOINED
        where = swarm.cell.copy()
    assert joined.any()


def test_a_shape_with_a_hole_is_warned_about_in_one_line():
    config = configure(SHAPES / "ring.png", strategy="self-assembly", cells=10, seed=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build(config)
    found = [w for w in caught if issubclass(w.category, ShapeWarning)]
    assert len(found) == 1 and "has a hole" in str(found[0].message)
    assert "self-assembly cannot form those" in str(found[0].message)
    assert "\n" not in str(found[0].message)


def test_the_packed_start_is_a_block_against_the_seeds():
    swarm = build(configure(SHAPES / "square.png", strategy="self-assembly", start="packed"))
    seeds = swarm.world.seeds
    touching = np.abs(swarm.cell[:, None, :] - seeds[None, :, :]).sum(axis=2) == 1
    assert touching.any()
    low, high = swarm.cell.min(axis=0), swarm.cell.max(axis=0)
    assert (high - low + 1).prod() == len(swarm.cell)  # 64 robots: an 8x8 block


def test_an_edge_follower_goes_straight_on_past_a_cell_without_stopping_on_it():
    """Every cell a start and a stop cost about five steps a cell at the default limits,
    against two at top speed: a follower under way now works out what it would do on the cell
    it is coming to, and goes on without braking when that is straight on. Before, it stopped
    on every cell it went straight past."""
    config = configure(
        SHAPES / "letter-k.png", strategy="self-assembly", cells=12, start="packed", seed=1
    )
    swarm = build(config)
    memory = swarm.driver.memory
    last, rested = np.zeros_like(swarm.cell), np.zeros(len(swarm.cell), dtype=bool)
    straight = stopped = 0
    for _ in range(600):
        before = swarm.cell.copy()
        swarm.step()
        way = swarm.cell - before
        following = (memory.state == OUTSIDE) | (memory.state == INSIDE)
        moved = np.flatnonzero(way.any(axis=1) & following)
        on = moved[(way[moved] == last[moved]).all(axis=1)]  # straight past its last cell
        straight += len(on)
        stopped += int(rested[on].sum())
        last[moved], rested[moved] = way[moved], False
        rested |= swarm.ahead == 0
    assert straight > 100
    assert stopped < straight / 2, "it stops only where something stops it"
    assert swarm.overlap_total == 0


def test_robots_that_hear_nothing_of_the_structure_walk_straight_on_to_find_it():
    """Scattered robots used to step at random, and spent most of a run searching: a random
    step repeats the last with a chance of a third at most, so its straight runs average under
    1.5 cells. Wanderers now walk straight on until blocked or they turn (`localise.roam`)."""
    swarm = build(configure(SHAPES / "small-square.png", strategy="self-assembly", seed=1))
    memory = swarm.driver.memory
    runs, length, last = [], np.zeros(len(swarm.cell), dtype=int), np.zeros_like(swarm.cell)
    for _ in range(600):
        before, wandering = swarm.cell.copy(), memory.state == WANDER
        swarm.step()
        step = swarm.cell - before
        for robot in np.flatnonzero(wandering & step.any(axis=1)):
            if (step[robot] == last[robot]).all():
                length[robot] += 1
            else:
                runs += [length[robot]] if length[robot] else []
                length[robot], last[robot] = 1, step[robot]
    assert len(runs) > 50
    assert np.mean(runs) > 3.0


def test_a_robot_inside_the_shape_never_steps_out_of_it_to_pass_a_follower():
    """Found re-running the comparison sweep: a robot inside the shape, stepping past a
    follower that faced it, turned from the wall and out of the shape, and joined there (its
    next move left the shape), so a cell stayed open for good. The move it judges is the one
    it makes."""
    swarm = formed("star.png", cells=10, seed=16)
    targets = {tuple(cell) for cell in swarm.world.targets.tolist()}
    joined = swarm.driver.memory.state == JOINED
    assert all(tuple(cell) in targets for cell in swarm.cell[joined].tolist())
    assert swarm.complete


def test_a_wanderer_the_structure_grew_round_joins_where_it_stands():
    """Scattered starts put robots on the shape's cells. Found re-running the paper's Fig. 4
    sweep: the structure grew round such a robot, every cell beside it taken, so it never
    started round the structure, and the followers behind it waited for it for good (the K at
    14 cells, seed 4: 59 % at step 8,000). It now starts too, and on the shape joins there."""
    swarm = formed("letter-k.png", cells=14, seed=4)
    assert swarm.complete
    assert swarm.overlap_total == 0


@pytest.mark.parametrize("rotation", [90, 270])
def test_two_followers_stopping_at_once_never_wall_a_free_cell_in(tmp_path, rotation):
    """Found turning a scenario's frame: the K at 16 cells turned a quarter, seed 3. Two
    followers stopped in the same step beside the same free cell, each taking the other for a
    robot passing by, and walled it in: 130 of 131 cells for good. One whose stop would wall
    it in if a follower at rest beside it that goes first stopped too now waits while that
    one stands there."""
    scenario = tmp_path / "turned.toml"
    scenario.write_text(
        f"[[groups]]\nshape = '{SHAPES / 'letter-k.png'}'\ncells = 16\n"
        f"pose = {{ x = 30, y = 25, rotation = {rotation} }}\n"
    )
    swarm = run(build(configure(scenario, strategy="self-assembly", seed=3)), max_steps=20_000)
    assert swarm.complete
    assert swarm.overlap_total == 0


def test_a_robot_never_stops_where_the_free_cells_beside_it_may_part():
    """Robots arriving round the structure from everywhere at once closed pockets longer than
    a robot's window sees whole (the S at 18 cells, seed 7: three cells walled in, 98.9 % for
    good). A robot about to stop where the free cells beside it lie apart within its window
    goes on into the shape instead."""
    swarm = formed("letter-s.png", cells=18, seed=7)
    assert swarm.complete
    assert swarm.overlap_total == 0


@pytest.mark.parametrize(("shape", "seed"), [("letter-s.png", 14), ("letter-k.png", 12)])
def test_followers_go_round_the_structure_one_way(shape, seed):
    """Found once wanderers set out every way (stop 50): robots that met the structure boxed in
    set off east whatever lay on their right, and one that stepped back to let a follower pass
    went on that way, so two streams went round opposite ways, met head on along one wall,
    where neither could step aside, and waited for good (the S at 18 cells, seed 14: 90.9 %
    after 60,000 steps; the K, seed 12: 71.1 %). Followers now keep the structure on their
    right."""
    swarm = formed(shape, cells=18, seed=seed)
    assert swarm.complete
    assert swarm.overlap_total == 0


def test_an_unknown_start_word_is_refused_and_a_csv_may_be_named_by_text(tmp_path):
    with pytest.raises(
        InputError, match="start must be packed, scatter or a CSV file of start cells, got 'pakced'"
    ):
        configure(SHAPES / "square.png", start="pakced")
    cells = tmp_path / "start.csv"  # as the environment and scripts pass it
    assert configure(SHAPES / "square.png", start=str(cells)).start == cells


def test_robots_beside_a_stalled_robot_go_round_it():
    """Drawn at random (`scripts/fuzz_programs.py self-assembly`, case 8): a robot stalls at
    step 161 beside the seeds, on the way round them. It is never heard, so the robots beside
    it waited to hear it for good (40 % at step 15,000); taken for stalled once unheard for
    `SILENCE` steps, it is a wall they go round."""
    fuzzed = ".#..#. ##.### #.##.. ..#### ###... #####. ..#... ##..#. #....# .##.##"
    shape = Shape(grid_from(fuzzed)).solid()
    world = build_world([GroupSpec("fuzz", shape, (1, 2, 3), 6)])
    params = RunConfig(msg_loss=0.1, distance_noise=0.1).params()
    faults = Faults((FaultEvent(161, "stall", 0.129733401782276),))
    swarm = Swarm(world, create("self-assembly"), 1536917474, params, faults=faults)
    swarm = run(swarm, max_steps=3000)
    assert (swarm.state == STALLED).sum() == 1
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_followers_go_round_a_robot_that_joined_beside_stalled_ones():
    """Fuzz case 7208 (scripts/fuzz_programs.py): robots stalled at step 191 pass no gradient
    on, and a robot that joined beside them had none; followers took it, without one, for a
    robot about to move, waited behind it for good, and the run never ended. A joined robot
    is a wall whatever its gradient: the run forms what the stalled robots leave reachable."""
    shape = Shape(grid_from("### ### .## ### ##. ### ### ### .##")).solid()
    world = build_world([GroupSpec("fuzz", shape, (1, 2, 3), 32)])
    faults = Faults((FaultEvent(191, "stall", 0.22065149815005852),))
    swarm = Swarm(world, create("self-assembly"), 599996301, RunConfig().params(), faults=faults)
    Runner(swarm, max_steps=3000).finish()
    assert swarm.complete and swarm.step_count < 3000
    joined = swarm.driver.memory.state == JOINED
    assert (swarm.state[joined] != STALLED).sum() == int(swarm.filled.sum())


def test_followers_stop_at_a_dead_end_that_stalled_robots_make():
    """Fuzz case 7251 (scripts/fuzz_programs.py): robots stalled at step 129, some inside the
    structure, left one-cell dead ends in it. A follower that found walls ahead and on both
    hands turned back into the follower behind it, each waiting for the other for good; and
    one beside a stalled robot took its cell for a pocket left free (`_pockets` saw only the
    structure) and waited to step into it for good. At step 3,000 the run stood at 44 %. A
    follower stops at a dead end, and stalled robots wall pockets in as the structure does."""
    fuzzed = "#.##.##.#. #..######. #.##.#.### ######..#. #.....###. ###..#...# #.#.####.. "
    fuzzed += "#.#.##.#.# ..###.#### ..##.##### ##.####.#."
    shape = Shape(grid_from(fuzzed)).solid()
    world = build_world([GroupSpec("fuzz", shape, (1, 2, 3), 86)])
    params = RunConfig(msg_loss=0.1, distance_noise=0.1).params()
    faults = Faults((FaultEvent(129, "stall", 0.1994635587672014),))
    swarm = Swarm(world, create("self-assembly"), 2106781546, params, faults=faults)
    Runner(swarm, max_steps=3000).finish()
    assert swarm.complete and swarm.step_count < 3000
    assert swarm.overlap_total == 0
    joined = swarm.driver.memory.state == JOINED
    assert (swarm.state[joined] != STALLED).sum() == int(swarm.filled.sum())


def test_a_run_whose_last_robots_stopped_comes_to_rest_under_noise():
    """The 8-cell ring (its hole is warned of: robots join only the edge of what is built),
    seed 1, with noisy senses: 37 robots joined, and three went round the structure without
    finding a cell and stopped. The stopped ones went on fixing their positions from noisy
    offsets, so their broadcasts changed every step, and the run never came to rest: it ran
    to the step cap. A stopped robot keeps its estimate, as a joined one does, and the run
    ends once all are still."""
    config = configure(SHAPES / "ring.png", strategy="self-assembly", cells=8, seed=1,
                       msg_loss=0.1, distance_noise=0.1)  # fmt: skip
    with pytest.warns(ShapeWarning, match="self-assembly cannot form those"):
        swarm = build(config)
    run(swarm, max_steps=5000)
    state = swarm.driver.memory.state
    assert (state == STOPPED).any() and np.isin(state, (JOINED, STOPPED)).all()
    assert swarm.driver.quiet and swarm.step_count < 5000

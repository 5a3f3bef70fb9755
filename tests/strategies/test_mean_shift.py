"""`mean-shift` (Sun et al. 2023 on the lattice) forms small shapes, holes and one-cell arms
included, within a bounded number of steps, the same run for the same seed, and reads its
options."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from PIL import Image
from scipy import ndimage

from swarmshape.check import InvariantWatch, watch_run
from swarmshape.config import RunConfig, configure
from swarmshape.core.faults import FaultEvent, Faults
from swarmshape.core.local import Memory
from swarmshape.core.metrics import run_metrics
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Blueprint, Perception
from swarmshape.core.shape import Shape
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.env.benchmark.baselines import policy
from swarmshape.env.benchmark.score import episode
from swarmshape.env.benchmark.suite import tasks
from swarmshape.io.bitmap import ShapeWarning
from swarmshape.runs import Runner, build, load_world, run, start_swarm
from swarmshape.strategies import create
from swarmshape.strategies.mean_shift import IN_PLACE, MESSAGE, OUTSIDE, MeanShift
from swarmshape.strategies.skills import relay
from swarmshape.strategies.skills import shape as skills
from swarmshape.strategies.skills.localise import localise
from tests.conftest import SHAPES, each_choice, grid_from, make_swarm, script, world_of


def formed(shape: str, max_steps: int = 3000, **settings):
    config = configure(SHAPES / shape, strategy="mean-shift", **settings)
    return run(build(config), max_steps=max_steps)


@pytest.mark.parametrize(
    ("shape", "cells", "seed"),
    each_choice(
        (*shape, seed)
        for shape in [("star.png", 12), ("ring.png", 10), ("horseshoe.png", None)]
        for seed in [0, 1, 2]
    ),
)
def test_small_shapes_with_arms_and_holes_form_whole_without_overlaps(shape, cells, seed):
    swarm = formed(shape, cells=cells, seed=seed)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0
    assert (swarm.driver.memory.state[swarm.present] == IN_PLACE).all()


def test_spare_robots_wait_outside_a_formed_shape():
    swarm = formed("star.png", cells=12, agents=60, seed=4)
    assert swarm.complete
    assert swarm.overlap_total == 0


def test_the_same_seed_gives_the_same_run():
    a, b = (formed("star.png", cells=12, seed=7) for _ in "ab")
    assert a.step_count == b.step_count
    assert np.array_equal(a.cell, b.cell)
    assert np.array_equal(a.driver.memory.news_hops, b.driver.memory.news_hops)


def test_without_the_entering_command_robots_outside_never_come_in():
    """The options reach the program: with the entering gain at 0 only robots that already
    sense a free cell of the shape move toward it, so most robots, scattered far off, never
    come in; with it the same start forms the shape."""
    still = formed("star.png", max_steps=400, cells=12, seed=5, options={"entering": 0.0})
    assert run_metrics(still)["coverage"] < 0.5
    assert formed("star.png", max_steps=3000, cells=12, seed=5).complete


def test_a_robot_in_the_rings_middle_is_let_in_by_a_hole_carried_to_it():
    """Every robot but one on the ring, that one in its middle, and the one empty cell on the
    outer rim: robots in place carry holes outward, away from the middle, so this hole must be
    carried in to it (`holes.pulled`; the 672-robot ring stopped a cell short for want of it)."""
    config = configure(SHAPES / "ring.png", strategy="mean-shift", cells=16, seed=0)
    world = load_world(config)
    targets = world.targets
    middle = np.floor(targets.mean(axis=0)).astype(np.int64)
    assert not (targets == middle).all(axis=1).any(), "the middle is off the ring"
    outermost = np.argmax(np.abs(targets - middle).sum(axis=1))
    start = np.concatenate([np.delete(targets, outermost, axis=0), [middle]])
    swarm = run(start_swarm(config, world, start), max_steps=2000)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_a_robot_beside_a_full_piece_goes_round_to_a_piece_no_robot_senses():
    """Two one-cell pieces farther apart than the sensing radius, one robot on each side:
    the robot beside the filled piece senses no empty cell and hears of none, so it walks the
    shape's rim cells in turn (`shape.tour`) until it senses the other (it stood beside the
    filled one for good)."""
    grid = np.zeros((4, 5), dtype=bool)
    grid[1, 1] = grid[3, 4] = True
    swarm = run(make_swarm(grid, agents=2, seed=0, strategy="mean-shift"), max_steps=2000)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_robots_outside_never_count_on_a_way_past_seeds_they_do_not_sense():
    """Two robots below the seeds, the one empty cell in reach past them: a seed beyond a
    robot's senses counted as free, so each step opened a way past the seeds that the next
    shut, and the two swapped places for ever (a random bitmap of the property test)."""
    rows = ["000111", "110110", "100000", "100011", "010010"]
    grid = np.array([[c == "1" for c in row] for row in rows])
    swarm = make_swarm(grid, agents=12, seed=3523526678, strategy="mean-shift")
    swarm = run(swarm, max_steps=3000)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_robots_outside_keep_going_where_news_of_empty_cells_sends_them():
    """The 299-robot K, seed 0, to step 300. Robots that had not yet worked out where they
    were took their frame cell for (0, 0) and made news of the cells beside it, filled long
    before (most robots outside gathered at the seeds' corner); and robots going round the
    shape the opposite ways met head-on and waited for each other (one stood 243 steps on one
    cell with a free cell beside it). News a robot makes names a cell of its shape not
    filled; no robot outside stands still for long beside a free cell."""
    swarm = build(configure(SHAPES / "letter-k.png", strategy="mean-shift", cells=24, seed=0))
    memory, group = swarm.driver.memory, swarm.world.groups[0]
    pairs = zip(group.frame_cells.tolist(), group.targets.tolist(), strict=True)
    world_of = {tuple(frame): cell for frame, cell in pairs}
    taken = np.zeros(swarm.world.size, dtype=bool)
    still = np.zeros(len(swarm.cell), dtype=np.int64)
    for _ in range(300):
        filled = swarm.filled.copy()  # as robots sensed them, at the step's start
        swarm.step()
        for robot in np.flatnonzero(memory.news_hops == 0):
            cell = world_of.get(tuple(memory.news[robot]))
            assert memory.localised[robot] and cell is not None, swarm.step_count
            assert not filled[swarm.target_at[tuple(cell)]], (swarm.step_count, robot)
        taken[:] = False
        taken[tuple(swarm.cell.T)] = taken[tuple(swarm.world.seeds.T)] = True
        padded = np.pad(taken, 1, constant_values=True)
        x, y = swarm.cell.T + 1
        beside = ~(padded[x - 1, y] & padded[x + 1, y] & padded[x, y - 1] & padded[x, y + 1])
        outside = (memory.state == OUTSIDE) & (swarm.ahead == 0)
        still = np.where(outside & beside, still + 1, 0)
        assert still.max() < 50, (swarm.step_count, np.flatnonzero(still >= 50))


def test_word_that_a_cell_is_taken_gives_way_to_newer_news_that_it_is_empty():
    """The 299-robot K, seed 8. Robots pass on word that the cell of some news is taken, so
    that robots far off drop it; without its age, word of a cell taken for a moment and
    news of it empty again chased each other round the swarm, robots dropping the news and
    taking it again every few steps, and the one robot left outside never kept it long
    enough to reach the cell (99.7 % at step 1,500)."""
    swarm = formed("letter-k.png", max_steps=1500, cells=24, seed=8)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_a_robot_outside_counts_no_way_through_cells_beyond_its_senses():
    """The 98-robot S, seed 0: the last robot outside stood above the middle bar, the last
    hole below it. The corners of its view square lie beyond its sensing radius, and counted
    free they made a way round the bar's end that robots in place blocked: it walked to and
    fro toward the hole for good (99.0 % at step 6,000)."""
    swarm = formed("letter-s.png", max_steps=1500, cells=14, seed=0)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_a_robot_following_news_goes_round_a_stalled_robot_in_its_way():
    """A property test's run: three robots stall at step 84, one of them on the straight way
    of a robot following news of an empty cell round the shape, which waited behind it for
    good (a stalled robot is silent, and never makes way)."""
    grid = grid_from("###.. ...#. ..#.# #....")
    world = build_world([GroupSpec("g", Shape(grid), (1, 2, 3), int(grid.sum()))])
    faults = Faults((FaultEvent(84, "stall", 0.4438385442748267),))
    swarm = run(Swarm(world, create("mean-shift"), 0, faults=faults), max_steps=700)
    assert (swarm.state == STALLED).sum() == 3
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


def test_robots_a_cell_off_in_their_frame_take_the_cell_their_neighbours_give():
    """The benchmark's noisy star, seed 1, once robots went round silent ones (the run took
    another way before): six robots round a hole held frame cells one cell off, counted the
    hole as filled and never carried it out (98.9 % at step 4,000). Robots at rest now check
    their cell against their neighbours at rest."""
    task = dataclasses.replace(tasks("star-100-noisy")[0], steps=600)
    result = episode(policy("mean-shift"), task, 1)
    assert result["formed"], result


def test_a_robot_a_cell_off_takes_its_cell_from_neighbours_nearer_the_seeds():
    """The 1,018-robot S under noise (message loss and distance noise 0.1, seed 1) stood at
    99.1 % for good: 196 robots held frame cells a cell off, each outvoted by its own block
    of neighbours, and nine of them stood outside the shape believing they were on it. Here
    robot 0 believes it is at (5, 0), a cell off; two neighbours of its block, as far from
    the seeds as it is, agree with it, and one nearer the seeds puts it at (4, 0). It takes
    (4, 0): only neighbours with fewer hops to the seeds (`anchor`) are asked."""
    offsets = np.array([[0.0, 1.0], [0.0, -1.0], [-1.0, 0.0]])
    cells = np.array([[5, 1], [5, -1], [3, 0]])  # what each neighbour says it holds
    memory = localised_beside(offsets, cells, hops=np.array([3, 3, 2]))
    assert memory.frame[0].tolist() == [4, 0]
    assert memory.anchor[0] == 3


def test_with_no_count_to_the_seeds_a_robot_a_cell_off_takes_its_cell_from_its_neighbours():
    """The star under noise (seed 0) stood at 99.7 % for good: its seeds stand cells away from
    the shape, so no robot at rest was within reach of them and none had hops to count, and a
    robot a cell off asked nobody; it stood off the star believing it was on it. Here no
    neighbour has hops; two put robot 0 at (4, 0), one at (5, 0) where it believes it is. It
    takes (4, 0)."""
    offsets = np.array([[0.0, 1.0], [0.0, -1.0], [-1.0, 0.0]])
    cells = np.array([[4, 1], [4, -1], [4, 0]])
    memory = localised_beside(offsets, cells, hops=np.full(3, relay.NONE))
    assert memory.frame[0].tolist() == [4, 0]
    assert memory.anchor[0] == relay.NONE


def localised_beside(offsets: np.ndarray, cells: np.ndarray, hops: np.ndarray) -> Memory:
    """Robot 0, localised at (5, 0) and at rest, after it localises among neighbours at rest
    at `offsets` that say they hold `cells` and have `hops` to the seeds."""
    n, m = 4, len(offsets)
    message = MESSAGE.pack(**{name: np.zeros((m, width), dtype=np.int64)
                              for name, width in MESSAGE.widths.items()})  # fmt: skip
    said = MESSAGE.read(message)
    said.localised[:], said.stays[:], said.cell[:] = 1, 1, cells
    said.anchor[:] = relay.said(hops, relay.NONE)
    everyone = np.ones(n, dtype=bool)
    sense = Perception(
        number=np.arange(n), group=np.zeros(n, dtype=np.int64), ready=everyone,
        heading=np.zeros(n, dtype=np.int64), cruising=~everyone, progress=np.zeros(n),
        moved=np.zeros((n, 2), dtype=np.int64), start=np.array([0, m, m, m, m]),
        owner=np.zeros(m, dtype=np.int64), offset=offsets, seed=np.zeros(m, dtype=bool),
        kin=np.ones(m, dtype=bool), heard=np.ones(m, dtype=bool), message=message,
        seed_frame=np.zeros((m, 2), dtype=np.int64), blueprint=Blueprint.of([cells]), step=9,
        radius=3.0,
    )  # fmt: skip
    memory = Memory(MeanShift.memory, n)
    memory.localised[:] = True
    memory.frame[0] = (5, 0)
    localise(sense, memory, said)
    return memory


SLOTS = np.ones((7, 7), dtype=bool)
SLOTS[2:5, 1] = SLOTS[1:6, 3] = False
"""A square round two slots."""


def test_holes_come_out_past_pockets_the_shape_encloses():
    """Depth counted straight across a slot left the cells beside it with no shape cell a step
    shallower, and a hole there never came out (every seed of this shape, and the 323-robot
    horse)."""
    swarm = run(make_swarm(SLOTS, seed=0, strategy="mean-shift"), max_steps=3000)
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


@given(bits=st.lists(st.booleans(), min_size=49, max_size=49))
@example(bits=SLOTS.ravel().tolist())
def test_every_shape_cell_deeper_than_the_rim_has_a_shallower_one_beside_it(bits):
    """Holes travel out one step shallower a move, so every cell of a piece that reaches the
    rim must have such a step (a piece inside a pocket, which no robot comes in to, need not)."""
    grid = np.array(bits).reshape(7, 7)
    if not grid.any():
        return
    cells = Shape(grid).cells
    blueprint = Blueprint.of([cells])
    groups = np.zeros(len(cells), dtype=np.int64)
    depth = skills.depth(blueprint, groups, cells)
    shallower = np.zeros(len(cells), dtype=bool)
    for step in STEPS[1:]:
        beside = cells + step
        there = skills.depth(blueprint, groups, beside)
        shallower |= blueprint.contains(groups, beside) & (there == depth - 1)
    pieces = ndimage.label(grid)[0][cells[:, 1], cells[:, 0]]
    reaches_rim = np.isin(pieces, pieces[depth == 1])
    assert (shallower | (depth == 1) | ~reaches_rim).all()


RIDGE = """
...#
#...
.##.
.#.#
##..
####
"""
"""A shape of single cells and short bars (`swarmshape check mean-shift --seed 100`, its second
shape) where a robot stops right above the seeds."""


def test_a_robot_where_the_ways_round_the_seeds_are_equally_long_takes_one():
    """Above the seeds, going round them left or right is as short, the entering command's two
    moves cancelled, and the robot stood there for good with the last cell open (92 % for
    20,000 steps); it now takes the first of them."""
    spec = GroupSpec("g", Shape(grid_from(RIDGE)), (1, 2, 3), 12)
    auto = build_world([spec])
    world = build_world([dataclasses.replace(spec, pose=auto.groups[0].pose)], (29, 17))
    watch = watch_run(world, MeanShift, 3034955526, max_steps=3000)
    assert watch.problems == []


def pocket_warnings(image: Path, strategy: str, **settings) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_world(configure(image, strategy=strategy, seed=1, **settings))
    return [str(w.message) for w in caught if issubclass(w.category, ShapeWarning)]


def ring_with_a_dot(folder: Path, side: int) -> Path:
    """A one-cell ring `side` cells across with a dot in its middle, drawn black on white."""
    image = folder / f"dot-in-a-ring-{side}.png"
    ink = np.zeros((side + 4, side + 4), dtype=bool)
    ink[2:-2, 2:-2] = True
    ink[3:-3, 3:-3] = False
    ink[side // 2 + 2, side // 2 + 2] = True
    Image.fromarray(np.where(ink, 0, 255).astype(np.uint8)).save(image)
    return image


def test_a_piece_that_only_pockets_touch_beyond_the_sensing_radius_is_warned_about(tmp_path):
    """A dot four cells inside a ring: no robot on the ring senses it empty (at the default
    radius of 3), so only a robot that starts in the ring's middle can fill it, and the run
    says so in one line. Two cells inside, or with robots that sense four cells, it forms
    (`holes.across_pockets`), and local-swap's robots, which trade and push their way across
    the shape, get no such warning."""
    far = ring_with_a_dot(tmp_path, 9)
    (said,) = pocket_warnings(far, "mean-shift", cells=9)
    assert "has 1 cell in pieces that only pockets of the shape touch" in said
    assert "beyond the sensing radius (3)" in said and "\n" not in said
    assert pocket_warnings(far, "mean-shift", cells=9, sense_radius=4) == []
    assert pocket_warnings(ring_with_a_dot(tmp_path, 5), "mean-shift", cells=5) == []
    assert pocket_warnings(far, "local-swap", cells=9) == []


@pytest.mark.parametrize("seed", range(10))
def test_robots_step_across_a_pocket_to_a_piece_that_only_pockets_touch(seed):
    """A dot two cells inside a ring, every robot but two spares on the ring: no robot outside
    reaches the dot and no hole carried out of the ring does, so a robot in place on the ring
    that senses it empty steps into the ring's middle and on to it, and the hole it leaves goes
    out to the spares. (Without that, 7 of these 10 seeds stood a cell short for good; the
    other 3 formed only because a robot that did not yet know where it was wandered in.)"""
    config = RunConfig(strategy="mean-shift", seed=seed)
    world = world_of(grid_from("##### #...# #.#.# #...# #####"), 16 + 2)
    targets = world.targets
    ring = targets[(targets != targets.mean(axis=0)).any(axis=1)]
    spares = targets.max(axis=0) + np.array([[3, 0], [3, 2]])
    watch = InvariantWatch()
    runner = Runner(start_swarm(config, world, np.concatenate([ring, spares])), [watch], 3000)
    swarm = runner.finish()
    assert swarm.complete, run_metrics(swarm)
    assert watch.problems == []


NESTED_RINGS = (
    "######### #.......# #.#####.# #.#...#.# #.#.#.#.# #.#...#.# #.#####.# #.......# #########"
)


@pytest.mark.parametrize("seed", range(10))
def test_of_robots_beside_a_pocket_the_one_nearest_an_empty_cell_steps_in(seed):
    """A dot in a ring in a ring, no spare robot, messages lost and distances noisy: two
    robots round the inner ring that sensed the dot empty stepped toward it at once, the one
    left over stood in its pocket for good, and the outer ring stayed a cell short (1 of
    these 10 seeds). Only the robot nearest the dot steps in (`holes._first_beside`)."""
    world = world_of(grid_from(NESTED_RINGS), 49)
    watch = InvariantWatch()
    config = RunConfig(strategy="mean-shift", seed=seed, msg_loss=0.1, distance_noise=0.1)
    swarm = Runner(start_swarm(config, world), [watch], max_steps=3000).finish()
    assert swarm.complete, run_metrics(swarm)
    assert watch.problems == []


FUZZED_SEALED = (
    "..##...# ##..#.#. ###.#### ##.#.### ##..#..# .####.## ..####.# .#..#.#. .###..#. "
    "######.. ######.#"
)


def test_a_one_cell_piece_walled_in_by_pockets_forms_with_noise_and_lost_messages():
    """Drawn at random (a fuzz): a one-cell piece whose four sides are pockets of the other
    pieces; with messages lost and distances noisy the run stood at 98.2 % for 15,000 steps."""
    world = world_of(grid_from(FUZZED_SEALED), 58)
    config = RunConfig(strategy="mean-shift", seed=1701060793, msg_loss=0.1, distance_noise=0.1)
    watch = InvariantWatch()
    swarm = Runner(start_swarm(config, world), [watch], max_steps=3000).finish()
    assert swarm.complete, run_metrics(swarm)
    assert watch.problems == []


def test_a_hole_behind_a_stalled_robot_moves_along_the_rim_to_the_robots_outside():
    """Every cell of a block filled but one in the middle of its far side, a robot stalled
    right outside that one and a spare robot farther out: no robot outside can reach the hole,
    and no robot inside moves to a cell as shallow as its own, so it stayed open for good;
    the robot in place beside it takes it, and the spare comes in to the cell it left
    (`holes.unwalled`)."""
    grid = np.ones((4, 7), dtype=bool)
    world = world_of(grid, int(grid.sum()) + 1)
    targets, seeds = world.targets, world.seeds
    side = np.argmax(np.abs(targets - seeds.mean(axis=0)).sum(axis=1))
    low, high = targets.min(axis=0), targets.max(axis=0)
    axis = int(targets[side, 0] in (low[0], high[0]))  # the far side runs along this axis
    far = targets[:, 1 - axis] == targets[side, 1 - axis]
    hole = targets[far][np.argsort(targets[far, axis])[int(far.sum()) // 2]]
    out = hole.copy()
    out[1 - axis] += 1 if hole[1 - axis] == high[1 - axis] else -1
    spare = out.copy()
    spare[1 - axis] += 3 if hole[1 - axis] == high[1 - axis] else -3
    keep = ~(targets == hole).all(axis=1)
    start = np.concatenate([targets[keep], [out, spare]])
    stall = FaultEvent(0, "stall", region=(int(out[0]), int(out[1]), 1, 1))
    config = RunConfig(strategy="mean-shift", seed=0, faults=(stall,))
    swarm = Runner(start_swarm(config, world, start), [], max_steps=400).finish()
    assert (swarm.state == STALLED).sum() == 1
    assert swarm.complete, run_metrics(swarm)
    assert swarm.overlap_total == 0


FUZZED_STALLS = (
    "########.## #..#######. ####..##### ########### ####.###.#. ########### ########..# "
    "#######.### ##..#.#####"
)


def test_robots_walled_in_by_stalled_robots_go_round_them_to_the_empty_cells():
    """Drawn at random (a fuzz, case 5): a fifth of the robots stall at step 55, and three of
    those left outside stand in a bay that stalled robots wall off from every empty cell. No
    cell they could walk to lay nearer along the way round the shape, so each stepped aside
    and back for good (81 % at step 15,000); they go round the stalled robots now
    (`explore.go_round`)."""
    world = world_of(grid_from(FUZZED_STALLS), 88)
    stall = FaultEvent(55, "stall", 0.18830150148731223)
    config = RunConfig(strategy="mean-shift", seed=1056080274, faults=(stall,))
    watch = InvariantWatch()
    swarm = Runner(start_swarm(config, world), [watch], max_steps=3000).finish()
    assert swarm.complete, run_metrics(swarm)
    assert watch.problems == []


@pytest.mark.parametrize(
    "number",
    [
        # A fault left too few robots: the shape formed with cells open and nobody outside,
        # and robots in place went on carrying holes toward robots that had pulled (waited
        # outside with no empty cell in sight) and gone in since: a count to a robot gone
        # climbs a step at a time (`relay`), and read as a pull until the cap. Found at stop
        # 63 on a rim pull that was taken back for it.
        pytest.param(16, id="formed-short-of-robots"),
        pytest.param(63, id="formed-short-of-robots-again"),
        # Two fewer robots than cells and no fault: the same, from the start's own shortage.
        pytest.param(22, id="fewer-robots-than-cells"),
    ],
)
def test_fuzzed_cases_keep_a_formed_shape_still(number):
    """Cases of ``scripts/fuzz_programs.py mean-shift`` (random shapes, noise, faults; every
    invariant watched): a formed shape, whole or short of robots, loses no cell while nothing
    changes it."""
    fuzz = script("fuzz_programs")
    assert fuzz.case(MeanShift, number, 15_000, 10.0) is None

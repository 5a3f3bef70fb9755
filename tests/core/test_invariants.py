"""Invariants that hold at every step, for random bitmaps, robot counts, arenas, seeds and
every strategy (hypothesis; more examples with ``pytest --slow``), watched by the same
`InvariantWatch` that ``swarmshape check`` uses."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.check import InvariantWatch
from swarmshape.core.faults import FaultEvent, Faults
from swarmshape.core.shape import Shape
from swarmshape.core.states import LOST, STALLED
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.runs import Runner
from swarmshape.strategies import available, create
from tests.conftest import each_choice, whole_runs

STRATEGIES = sorted(available())


def watched(swarm: Swarm, steps: int) -> InvariantWatch:
    """Step under the watch until the run would end (formed, gone quiet or stranded, with no
    fault to come), then as long again beyond it, as a window goes on showing it; under a
    failure rate, which strikes at any step, the whole budget of `steps`."""
    watch = InvariantWatch()
    runner = Runner(swarm, [watch], max_steps=steps)
    while not runner.finished:
        runner.step()
    if swarm.faults.rate == 0:
        runner.max_steps = min(steps, 2 * swarm.step_count)
    while not runner.out_of_steps:
        runner.step()
    return watch


@pytest.mark.parametrize("strategy", STRATEGIES)
@settings(deadline=None, max_examples=whole_runs(len(STRATEGIES)))
@given(
    bits=st.lists(st.booleans(), min_size=20, max_size=20),
    spare=st.integers(-3, 6),
    room=st.integers(0, 12),
    seed=st.integers(0, 2**32 - 1),
)
def test_invariants_hold_at_every_step(strategy, bits, spare, room, seed):
    """The examples are shared out over the strategies, so each gets its share."""
    grid = np.array(bits).reshape(4, 5)
    if not grid.any():
        grid[1, 1] = True
    agents = max(1, int(grid.sum()) + spare)
    spec = GroupSpec("g", Shape(grid), (1, 2, 3), agents)
    auto = build_world([spec])
    arena = (auto.size[0] + room, auto.size[1] + room // 2)
    world = build_world([spec], arena)
    steps = 400 if strategy != "paper" else 1500
    swarms = [Swarm(world, create(strategy), seed) for _ in "ab"]
    watches = [watched(swarm, steps) for swarm in swarms]
    assert watches[0].problems == []
    assert swarms[0].overlap_total == 0
    assert watches[0].digest.digest() == watches[1].digest.digest(), "deterministic per seed"
    assert np.array_equal(swarms[0].cell, swarms[1].cell)
    assert np.array_equal(swarms[0].state, swarms[1].state)


@pytest.mark.parametrize("strategy", STRATEGIES)
@settings(deadline=None, max_examples=whole_runs(3 * len(STRATEGIES)))
@given(
    bits=st.lists(st.booleans(), min_size=20, max_size=20),
    spare=st.integers(-3, 6),
    seed=st.integers(0, 2**32 - 1),
    events=st.lists(
        st.tuples(
            st.integers(0, 300),
            st.sampled_from(["remove", "stall"]),
            st.one_of(st.floats(0.05, 0.6), st.integers(1, 4)),
            st.one_of(
                st.none(),
                st.tuples(
                    st.integers(0, 12), st.integers(0, 8), st.integers(1, 6), st.integers(1, 6)
                ),
                st.tuples(st.integers(0, 12), st.integers(0, 8), st.integers(1, 4)),
            ),
        ),
        max_size=3,
    ),
    rate=st.sampled_from([0.0, 0.0, 0.002]),
    second=st.one_of(st.none(), st.lists(st.booleans(), min_size=20, max_size=20)),
)
def test_invariants_hold_through_random_faults(strategy, bits, spare, seed, events, rate, second):
    """Random fault events and failure rates, on one group or two: no overlaps, robots
    conserved except those removed, settled robots stay, the same run per seed, and every shape
    heals or rescales. (With `--slow`, a third of the plain test's examples: each runs up to
    2,500 steps twice.)"""
    hold_through_faults(strategy, bits, spare, seed, events, rate, second)


STALLED_ON_A_GOAL = [
    [bit == "#" for bit in "##.#.#.###...##.#.#."],
    [bit == "#" for bit in "##...#.###...##.#.#."],
]
FAULT_CASES = {
    # issue 29: a group re-formed smaller renumbered the other group's targets, and a robot of
    # that group not yet sent off went for an index past the end (two-squares.toml, seed 5,
    # optimal)
    "another-group-re-formed-smaller": ("optimal", dict(
        bits=[True] * 20, spare=0, seed=0, events=[(0, "remove", 1, None)], rate=0.0,
        second=[True] * 20,
    )),
    # hypothesis found both: local-swap robots kept goals under robots stalled at step 32, and
    # one waited beside its goal for ever, the other traded it into the formed shape
    "a-goal-under-a-stalled-robot": ("local-swap", dict(
        bits=STALLED_ON_A_GOAL[0], spare=-2, seed=579, events=[(32, "stall", 0.3391, None)],
        rate=0.0, second=None,
    )),
    "a-goal-traded-into-the-formed-shape": ("local-swap", dict(
        bits=STALLED_ON_A_GOAL[1], spare=-2, seed=0, events=[(32, "stall", 0.3391, None)],
        rate=0.0, second=None,
    )),
    # hypothesis found it: a stall on the one cell left after removals at step 0 left no copy
    # to re-form at the seeds, so the run never formed nor ended stranded
    "no-copy-left-at-the-seeds": ("local-swap", dict(
        bits=[bit == "#" for bit in "#..#...#..#.#..#.#.#"], spare=-3, seed=946,
        events=[(120, "stall", 0.39587348908824527, None),
                (0, "remove", 0.08094609668464764, None),
                (0, "remove", 0.5900099683931079, None)],
        rate=0.0, second=None,
    )),
    # hypothesis found it: the shape formed the step 4 robots stalled, and one coasting on the
    # step after stopped walling off a cell, which opened it again
    "a-stalled-robot-coasting-on": ("local-swap", dict(
        bits=[bit == "#" for bit in "#.##.#....#.#.####.."], spare=-1, seed=150,
        events=[(0, "remove", 0.05, None), (157, "stall", 4, (6, 0, 5, 5))], rate=0.0,
        second=None,
    )),
    # the fault property found it (greedy): robots stalled at step 43 were still coasting when
    # the run read the cells they walled off as lost, ended it formed, and stopped a step later
    # with those cells open again
    "ended-while-a-wall-coasted": ("greedy", dict(
        bits=[bit == "#" for bit in ".#....#######.#..#.#"], spare=-1, seed=43,
        events=[(43, "stall", 0.375, None)], rate=0.0, second=None,
    )),
}  # fmt: skip
"""Examples that broke the fault property once, each with the strategy it broke; each is run
under every strategy (by default under that one, and each strategy once, `each_choice`)."""


@pytest.mark.parametrize(
    ("strategy", "case"),
    each_choice(
        itertools.product(STRATEGIES, FAULT_CASES),
        keep=[(broken, case) for case, (broken, _) in FAULT_CASES.items()],
    ),
)
def test_fault_runs_that_once_broke_an_invariant(strategy, case):
    hold_through_faults(strategy, **FAULT_CASES[case][1])


def hold_through_faults(strategy, bits, spare, seed, events, rate, second):
    """Two runs of one case of the fault property, watched at every step."""
    specs = []
    for name, picture in (("g", bits), ("h", second)):
        if picture is None:
            continue
        grid = np.array(picture).reshape(4, 5)
        if not grid.any():
            grid[1, 1] = True
        specs.append(GroupSpec(name, Shape(grid), (1, 2, 3), max(1, int(grid.sum()) + spare)))
    world = build_world(specs)
    schedule = tuple(FaultEvent(*event) for event in events)
    # a budget per group: groups form side by side and their robots share the arena's traffic
    steps = (700 if strategy != "paper" else 2500) * len(specs)
    swarms = [Swarm(world, create(strategy), seed, faults=Faults(schedule, rate)) for _ in "ab"]
    watches = [watched(swarm, steps) for swarm in swarms]
    assert watches[0].problems == []
    assert swarms[0].overlap_total == 0
    assert watches[0].digest.digest() == watches[1].digest.digest(), "deterministic per seed"
    assert swarms[0].faults.log == swarms[1].faults.log
    able = (swarms[0].state != LOST) & (swarms[0].state != STALLED)
    # with none able to move, the run ends unformed (by design); a program that grows from its
    # seeds never moves a joined robot again, so it cannot heal (see test_faults.py)
    repairs = not getattr(available()[strategy], "grows_from_seeds", False)
    if rate == 0 and able.any() and repairs:
        assert swarms[0].complete, "the shape heals, or re-forms smaller, after its faults"

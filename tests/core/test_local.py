"""Local programs: what a robot senses, what the core does with its moves, and that nothing
absolute leaks into a program."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmshape.core.local import Memory, Program, ProgramError, Schema, Slot, _link_up
from swarmshape.core.perception import Perception, Senses, neighbours
from swarmshape.core.shape import Pose, Shape
from swarmshape.core.states import SETTLED
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.runs import run


class East(Program):
    """Every robot tries to go east, forever, and says how far it has gone."""

    name = "east"
    description = "test: always east"
    message_size = 1
    memory: ClassVar[dict[str, Slot]] = {"went": Slot(np.int64, 0)}

    def act(self, sense: Perception, memory: Memory, rng: np.random.Generator):
        memory.went += sense.moved[:, 0]
        return np.full(len(sense), 1), memory.went[:, None].copy()


class Drift(Program):
    """Robots step away from their nearest neighbour, tell how many they sense, and sometimes
    step at random: a program that uses offsets, messages and the generator."""

    name = "drift"
    description = "test: spread out"
    message_size = 1

    def act(self, sense: Perception, memory: Memory, rng: np.random.Generator):
        count = np.bincount(sense.owner, minlength=len(sense))
        away = np.zeros((len(sense), 2))
        np.add.at(away, sense.owner, -sense.offset * (sense.message[:, :1] + 1))
        along_x = np.abs(away[:, 0]) >= np.abs(away[:, 1])
        x_way, y_way = np.where(away[:, 0] > 0, 1, 2), np.where(away[:, 1] > 0, 3, 4)
        moves = np.where(along_x, x_way, y_way)
        moves[count == 0] = 0
        jump = rng.random(len(sense)) < 0.2
        moves[jump] = rng.integers(0, 5, jump.sum())
        return moves, count[:, None]


def world_of(grid: np.ndarray, agents: int, pose: Pose | None = None, arena=(20, 12)):
    pose = pose or Pose(2, 2)
    return build_world([GroupSpec("g", Shape(grid), (1, 2, 3), agents, pose)], arena)


def test_neighbours_are_exactly_those_within_the_radius():
    rng = np.random.default_rng(1)
    cells = rng.permutation(np.argwhere(np.ones((12, 9), dtype=bool)))[:40]
    seeds = cells[:3]
    robots = cells[3:]
    reach = Senses(radius=2.5).reach()
    start, owner, other = neighbours(robots, seeds, (12, 9), reach)
    everything = np.concatenate([robots, seeds])
    for i, cell in enumerate(robots):
        near = np.hypot(*(everything - cell).T)
        expected = set(np.flatnonzero((near <= 2.5) & (near > 0)).tolist())
        assert set(other[start[i] : start[i + 1]].tolist()) == expected
        assert (owner[start[i] : start[i + 1]] == i).all()


def test_a_move_into_a_taken_cell_does_not_happen_and_odometry_says_so():
    world = world_of(np.ones((1, 3), dtype=bool), 3, arena=(12, 6))
    start = np.array([[7, 4], [8, 4], [9, 4]])
    swarm = Swarm(world, East(), seed=1, start=start)
    run(swarm, max_steps=60)
    assert swarm.overlap_total == 0
    assert sorted(swarm.cell[:, 0].tolist()) == [9, 10, 11]  # queued against the east wall
    assert (swarm.driver.memory.went == swarm.cell[:, 0] - start[:, 0]).all()


def test_a_move_the_lattice_refuses_is_counted_as_refused():
    world = world_of(np.ones((1, 3), dtype=bool), 2, arena=(12, 6))
    swarm = Swarm(world, East(), seed=1, start=np.array([[11, 4], [5, 4]]))
    for _ in range(5):
        swarm.step()
    # the first robot asks for the wall every step; the second is under way, its claims won
    assert swarm.driver.refused == 5


class EastThenSouth(Program):
    """East until the robot has gone (or is on its way to) 10 cells, then south: asked to
    turn while under way, it must brake and stop first."""

    name = "east-then-south"
    description = "test: a turn"
    memory: ClassVar[dict[str, Slot]] = {"went": Slot(np.int64, 0)}

    def act(self, sense: Perception, memory: Memory, rng: np.random.Generator):
        memory.went += np.abs(sense.moved).sum(axis=1)
        committed = memory.went + (sense.heading > 0)  # the cell reserved ahead is coming
        return np.where(committed < 10, 1, 3), np.zeros((len(sense), 0), dtype=np.int64)


def test_a_robot_that_keeps_choosing_its_way_cruises_and_stops_only_to_turn():
    world = world_of(np.ones((1, 1), dtype=bool), 1, arena=(40, 30))
    swarm = Swarm(world, EastThenSouth(), seed=1, start=np.array([[6, 10]]))
    stops, speeds = 0, []
    for _ in range(60):
        swarm.step()
        speeds.append(float(swarm.speed[0]))
        stops += swarm.ahead[0] == 0
    assert swarm.cell[0, 0] == 16, "east ten cells, then only south"
    top = swarm.params.limits.max_speed
    east = speeds[: speeds.index(0.0)]
    assert east.count(top) >= 14, "ten cells at top speed but for speeding up and braking"
    assert 0.0 not in speeds[3 : len(east)], "no stop on the way east"
    assert swarm.cell[0, 1] > 15 and swarm.overlap_total == 0


def test_a_program_returning_nonsense_is_one_clear_error():
    class Wild(East):
        name = "wild"

        def act(self, sense, memory, rng):
            return np.full(len(sense), 9), np.zeros((len(sense), 1), dtype=np.int64)

    world = world_of(np.ones((1, 3), dtype=bool), 3)
    with pytest.raises(ProgramError, match=r"not 0 .stay. to 4"):
        Swarm(world, Wild(), seed=1).step()


def test_a_lost_link_is_lost_both_ways():
    world = world_of(np.ones((3, 4), dtype=bool), 12)
    swarm = Swarm(world, Drift(), seed=3, params=Params(senses=Senses(msg_loss=0.5)))
    sense = swarm.driver.perceive()
    _, owner, other = neighbours(
        swarm.cell, swarm.world.seeds, swarm.world.size, swarm.params.senses.reach()
    )
    heard = {(int(a), int(b)): bool(h) for a, b, h in zip(owner, other, sense.heard, strict=True)}
    links = [(a, b) for (a, b) in heard if b < len(swarm.cell)]
    assert links
    assert all(heard[(a, b)] == heard[(b, a)] for a, b in links)
    a, b = np.random.default_rng(0).integers(0, 10**6, size=(2, 20_000))
    assert 0.48 < _link_up(a, b, salt=12345, loss=0.5).mean() < 0.52
    assert (_link_up(a, b, 7, 0.3) == _link_up(b, a, 7, 0.3)).all()


def test_a_removed_robot_is_gone_from_perception_and_a_stalled_one_is_silent_and_still():
    world = world_of(np.ones((1, 3), dtype=bool), 4, arena=(14, 6))
    start = np.array([[6, 4], [7, 4], [8, 4], [9, 4]])
    swarm = Swarm(world, East(), seed=1, start=start)
    swarm.fail(np.array([1]), "remove")
    swarm.fail(np.array([2]), "stall")
    sense = swarm.driver.perceive()
    row = slice(sense.start[0], sense.start[1])
    robots = ~sense.seed[row]
    offsets, heard = sense.offset[row][robots].tolist(), sense.heard[row][robots]
    sensed = {tuple(o): h for o, h in zip(offsets, heard, strict=True)}
    assert sensed == {(2.0, 0.0): False, (3.0, 0.0): True}  # 1 is gone, 2 is there but silent
    assert sense.start[2] == sense.start[1]  # the removed robot senses nothing
    assert not sense.ready[[1, 2]].any()
    run(swarm, max_steps=60)
    assert swarm.overlap_total == 0
    assert swarm.cell[:, 0].tolist() == [7, 7, 8, 13]  # 0 stops behind the stalled robot


WALL_FREE_STEPS = 60
"""Steps in which no robot can reach the arena's walls (at most half a cell a step, and 32 cells
of room): walls do not move with the scenario."""


@settings(max_examples=12, deadline=None)
@given(
    dx=st.integers(0, 6),
    dy=st.integers(0, 6),
    turns=st.integers(0, 3),
    seed=st.integers(0, 2**16),
    noisy=st.booleans(),
)
def test_a_translated_scenario_runs_the_same_translated(dx, dy, turns, seed, noisy):
    """No absolute position leaks into a program: moving the whole scenario (shape, seeds and
    robots) moves the run, step for step (cells moved, the rest identical)."""
    grid = np.array([[1, 1, 1, 0], [1, 1, 1, 1], [0, 1, 1, 0]], dtype=bool)
    senses = Senses(distance_noise=0.05, msg_loss=0.1) if noisy else Senses()
    pose = Pose(34, 34, 90 * turns)
    runs = []
    for shift in ((0, 0), (dx, dy)):
        moved = Pose(pose.x + shift[0], pose.y + shift[1], pose.rotation)
        world = world_of(grid, 12, moved, arena=(80 + dx, 80 + dy))
        start = np.argwhere(np.ones((3, 4), dtype=bool)) + np.array([42, 42]) + shift
        swarm = Swarm(world, Drift(), seed, Params(senses=senses), start)
        trail = []
        for _ in range(WALL_FREE_STEPS):
            swarm.step()
            trail.append(np.column_stack([swarm.cell - shift, swarm.direction, swarm.offset]))
        runs.append(np.array(trail))
    assert np.array_equal(runs[0], runs[1])


def test_a_message_schema_packs_and_reads_fields_by_name():
    schema = Schema(state=1, position=2, hops=1)
    assert len(schema) == 4
    message = schema.pack(state=[1, 2], position=[[3, 4], [5, 6]], hops=np.array([7, 8]))
    assert message.dtype == np.int64 and message.tolist() == [[1, 3, 4, 7], [2, 5, 6, 8]]
    fields = schema.read(message)
    assert fields.state.tolist() == [1, 2] and fields.position.tolist() == [[3, 4], [5, 6]]
    with pytest.raises(TypeError, match="exactly the fields state, position, hops"):
        schema.pack(state=[1], position=[[0, 0]])


class Still(Program):
    """Robots that never move and never say they are done."""

    name = "still"
    description = "test: stay"

    def act(self, sense: Perception, memory: Memory, rng: np.random.Generator):
        return np.zeros(len(sense), dtype=np.int64), np.zeros((len(sense), 0), dtype=np.int64)


class StillDone(Still):
    """The same, every other robot done for good."""

    name = "still-done"

    def finished(self, memory: Memory) -> np.ndarray:
        return np.arange(len(memory)) % 2 == 0


def test_a_program_that_does_not_say_when_robots_are_done_fills_the_targets_they_rest_on():
    """Issue 29, case 19: the README's Gather (no finished()) reported coverage 0 % while its
    robots rested on the shape."""
    world = world_of(np.ones((1, 4), dtype=bool), 4, arena=(12, 6))
    start = np.array([*world.targets[:3].tolist(), world.start_cells()[0].tolist()])
    for program, filled, settled in ((Still(), 3, 0), (StillDone(), 2, 2)):
        swarm = Swarm(world, program, seed=1, start=start)
        run(swarm, max_steps=3)
        assert swarm.filled.sum() == filled, program.name
        assert (swarm.state == SETTLED).sum() == settled, program.name

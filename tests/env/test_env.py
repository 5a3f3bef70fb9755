"""The learning environment keeps PettingZoo's and Gymnasium's conventions, shows the robots
exactly what a local program senses, and is deterministic per seed."""

from __future__ import annotations

import dataclasses
import warnings
from typing import ClassVar

import numpy as np
import pytest
from gymnasium.utils import env_checker
from gymnasium.utils.passive_env_checker import (
    check_action_space,
    check_observation_space,
    env_reset_passive_checker,
)
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, seed_test

import swarmshape.env as learn
from swarmshape.core.local import Memory, Program, Slot
from swarmshape.core.motion import STEPS
from swarmshape.core.perception import Perception
from swarmshape.core.shape import Shape
from swarmshape.core.states import LOST, STALLED
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import GroupSpec, build_world, packed_start
from swarmshape.env.observe import OWN
from swarmshape.errors import InputError
from swarmshape.runs import Runner, start_swarm
from swarmshape.strategies import create

SQUARE = np.ones((3, 3), dtype=bool)


def small(**options):
    return learn.parallel_env(SQUARE, max_steps=30, **options)


def test_pettingzoo_parallel_api_test_passes():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # its warnings name broken conventions: none allowed
        parallel_api_test(small(message_size=2), num_cycles=100)


def test_pettingzoo_seed_tests_pass():
    parallel_seed_test(lambda: small(message_size=2))
    seed_test(lambda: learn.raw_env(shape=SQUARE, max_steps=30), num_cycles=50)


def test_pettingzoo_aec_api_test_passes_on_the_converted_environment():
    """The AEC test also checks dtypes, observations within their space and flag types."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        api_test(learn.raw_env(shape=SQUARE, max_steps=30), num_cycles=100)
        # with messages the action space is MultiDiscrete, which the test merely advises against
        warnings.filterwarnings("ignore", "Action space for each agent probably should be")
        aec = learn.raw_env(shape=SQUARE, max_steps=30, message_size=1, message_range=(3, 6))
        api_test(aec, num_cycles=100)  # messages not heard yet read 0, outside 3..6


def test_created_through_pettingzoos_registry():
    import pettingzoo

    made = pettingzoo.make("parallel", learn.ID, shape=SQUARE, max_steps=5)
    assert isinstance(made, learn.SwarmEnv)


def test_gymnasiums_checks_that_apply_to_the_batched_interface_pass():
    vec = learn.vector_env(SQUARE, max_steps=30, message_size=2, message_range=(-3, 3))
    for space in (vec.single_observation_space, vec.observation_space):
        check_observation_space(space)
    for space in (vec.single_action_space, vec.action_space):
        check_action_space(space)
    env_checker.check_reset_return_type(vec)
    env_checker.check_reset_seed_determinism(vec)
    env_checker.check_reset_options(vec)
    env_reset_passive_checker(vec)
    # check_step_determinism and check_returned_data_not_reused expect one flag per step, not
    # one per robot; the same checks, batched:
    vec.action_space.seed(5)
    actions = vec.action_space.sample()
    first = [vec.reset(seed=5), vec.step(actions)]
    again = [vec.reset(seed=5), vec.step(actions)]
    assert env_checker.data_equivalence(first, again, exact=True)
    obs, rewards, terminated, truncated, _ = first[1]
    assert obs in vec.observation_space
    assert rewards.shape == terminated.shape == truncated.shape == (vec.num_envs,)
    assert terminated.dtype == truncated.dtype == bool and not truncated.any()
    assert not env_checker.data_shares_objects(first[0], first[1])
    assert not env_checker.data_shares_objects(first[1], again[1])


def rollout(env, seed, steps):
    """Observations and rewards of `steps` random steps, actions drawn from a seeded space."""
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    seen = [obs]
    for _ in range(steps):
        obs, rewards, *_ = env.step(env.action_space.sample())
        seen += [obs, rewards]
    return seen


def test_the_same_seed_gives_the_same_episode_and_another_seed_another():
    options = dict(max_steps=200, distance_noise=0.1, msg_loss=0.2, message_size=1)
    one = rollout(learn.vector_env("shapes/star.png", cells=8, **options), 7, 60)
    two = rollout(learn.vector_env("shapes/star.png", cells=8, **options), 7, 60)
    other = rollout(learn.vector_env("shapes/star.png", cells=8, **options), 8, 60)
    assert env_checker.data_equivalence(one, two, exact=True)
    assert not env_checker.data_equivalence(one[0], other[0])


class Nearest(Program):
    """A deterministic program (no random draws): step away from the nearest neighbour on the
    longer axis, or toward the first seed heard; broadcast the step count and its number."""

    name = "nearest"
    description = "test"
    message_size = 2
    memory: ClassVar[dict[str, Slot]] = {}
    seen: list[Perception]

    def act(self, sense, memory, rng):
        self.seen.append(sense)
        return nearest_moves(sense), np.column_stack([sense.number, sense.number * 0 + sense.step])


def nearest_moves(sense: Perception) -> np.ndarray:
    n = len(sense)
    first = sense.start[:-1]
    has = sense.start[1:] > first
    offset = np.zeros((n, 2))
    offset[has] = sense.offset[first[has]]
    away = np.where(sense.seed[np.minimum(first, len(sense.owner) - 1)][:, None], 1, -1) * offset
    along_x = np.abs(away[:, 0]) >= np.abs(away[:, 1])
    step = np.where(along_x[:, None], [[1, 0]], [[0, 1]]) * np.sign(away)
    moves = np.array([np.flatnonzero((s == STEPS).all(axis=1))[0] for s in step.astype(int)])
    return np.where(has, moves, (sense.number + sense.step) % 5)


def test_the_environment_shows_each_robot_exactly_what_a_local_program_senses():
    """The same program run by the swarm itself and run through the environment (decoding its
    observations) senses the same and moves the same, step for step, noise and losses too."""
    options = dict(max_steps=80, distance_noise=0.2, msg_loss=0.3, message_size=2)
    vec = learn.vector_env("shapes/star.png", cells=8, message_range=(0, 1000), **options)
    obs, _ = vec.reset(seed=3)
    episode = vec.episode
    program = Nearest()
    program.seen = []
    config = dataclasses.replace(episode.config, seed=episode.swarm.seed)
    itself = start_swarm(config, episode.world, None, program)
    for _ in range(60):
        itself.step()
        sense = learn.perception_of(obs, episode.layout, episode.control.blueprint)
        expected = program.seen[-1]
        for field in dataclasses.fields(Perception):
            mine, theirs = getattr(sense, field.name), getattr(expected, field.name)
            if field.name in ("offset", "progress"):  # float32 in an observation
                np.testing.assert_allclose(mine, theirs, atol=1e-5)
            elif field.name != "blueprint":
                np.testing.assert_array_equal(mine, theirs, err_msg=field.name)
        moves = nearest_moves(sense)
        messages = np.column_stack([sense.number, sense.number * 0 + sense.step])
        obs, *_ = vec.step(np.column_stack([moves, messages]))
        np.testing.assert_array_equal(episode.swarm.cell, itself.cell)
    assert itself.step_count == 60 and len(program.seen) == 60


def test_fewer_slots_keep_the_nearest_neighbours():
    full = learn.vector_env("shapes/star.png", cells=8)
    few = learn.vector_env("shapes/star.png", cells=8, neighbours=2)
    a, _ = full.reset(seed=1)
    b, _ = few.reset(seed=1)
    assert b.shape == (len(a), len(OWN) + 2 * 8)
    np.testing.assert_array_equal(b, a[:, : b.shape[1]])


def towards_the_targets(env) -> dict[str, int]:
    """A policy that cheats (it reads the swarm): each robot steps down a distance field to the
    open target cells, round the seeds, from the cell it rests on or will rest on next (a robot
    under way asked to go on straight does). Enough to test what happens when the shape is
    formed."""
    swarm = env.episode.swarm
    world = swarm.world
    far = np.iinfo(np.int64).max // 2
    distance = np.full(world.size, far)
    distance[tuple(world.targets[~swarm.filled].T)] = 0
    blocked = np.zeros(world.size, dtype=bool)
    blocked[tuple(world.seeds.T)] = True
    for _ in range(sum(world.size)):  # relax until settled
        padded = np.pad(distance, 1, constant_values=far)
        nearest = np.min([padded[1 + dx : padded.shape[0] - 1 + dx, 1 + dy : padded.shape[1] - 1
                          + dy] for dx, dy in STEPS[1:]], axis=0)  # fmt: skip
        distance = np.where(blocked, far, np.minimum(distance, nearest + 1))
    moves = {}
    for index, agent in enumerate(env.agents):
        cell = swarm.cell[index] + STEPS[swarm.direction[index]] * swarm.ahead[index]
        ahead = cell + STEPS[1:]
        inside = ((ahead >= 0) & (ahead < world.size)).all(axis=1)
        value = np.where(inside, distance[tuple(np.clip(ahead, 0, np.array(world.size) - 1).T)],
                         far)  # fmt: skip
        best = int(value.argmin())
        moves[agent] = best + 1 if value[best] < distance[tuple(cell)] else 0
    return moves


def test_forming_the_shape_terminates_every_agent_and_the_rewards_add_up_to_coverage():
    env = learn.parallel_env(np.ones((1, 2), dtype=bool), max_steps=500)
    env.reset(seed=4)
    total = 0.0
    for _ in range(500):
        _, rewards, terminations, truncations, _ = env.step(towards_the_targets(env))
        total += sum(rewards.values())
        if any(terminations.values()):
            break
    assert all(terminations.values()) and not any(truncations.values())
    assert set(terminations) == set(env.possible_agents)
    assert env.agents == [] and env.coverage() == 1.0
    assert env.state() in env.state_space
    assert total == pytest.approx(1.0)  # the rewards add up to the change in coverage
    assert env.step({}) == ({}, {}, {}, {}, {})


def test_the_step_limit_truncates_and_the_batched_interface_resets_on_the_next_step():
    vec = learn.vector_env(SQUARE, max_steps=3)
    vec.reset(seed=1)
    stay = np.zeros(vec.num_envs, dtype=np.int64)
    flags = [vec.step(stay)[3].all() for _ in range(3)]
    assert flags == [False, False, True]
    _, rewards, terminated, truncated, _ = vec.step(stay)  # NEXT_STEP autoreset
    assert not truncated.any() and not terminated.any() and not rewards.any()
    assert vec.episode.swarm.step_count == 0
    with pytest.raises(ValueError, match="every robot"):
        vec.reset(options={"reset_mask": np.arange(vec.num_envs) == 0})


def test_any_callable_can_be_the_reward():
    class Spread:
        """Rewards robots by how far they are from robot 0; told of each new episode."""

        episodes = 0

        def reset(self, swarm):
            self.episodes += 1

        def __call__(self, swarm):
            return np.abs(swarm.cell - swarm.cell[0]).sum(axis=1).astype(float)

    spread = Spread()
    vec = learn.vector_env(SQUARE, reward=spread)
    vec.reset(seed=1)
    _, rewards, *_ = vec.step(np.zeros(vec.num_envs, dtype=np.int64))
    assert spread.episodes == 1 and rewards[0] == 0 and rewards[1:].min() > 0
    plain = learn.vector_env(SQUARE, reward=lambda swarm: np.ones(2))
    plain.reset(seed=1)
    with pytest.raises(ValueError, match="the reward gave shape"):
        plain.step(np.zeros(plain.num_envs, dtype=np.int64))


@pytest.mark.parametrize("shape", ["shapes/star.png", SQUARE])
def test_robots_may_start_packed_against_the_seeds(shape):
    vec = learn.vector_env(shape, cells=8 if isinstance(shape, str) else None, start="packed")
    vec.reset(seed=1)
    swarm = vec.episode.swarm
    assert (swarm.cell == packed_start(swarm.world)).all()


def test_an_episode_is_1000_steps_unless_told():
    assert learn.vector_env(SQUARE).episode.max_steps == learn.EPISODE_STEPS == 1000
    assert learn.vector_env(SQUARE, max_steps=None).episode.max_steps == 1000
    assert learn.vector_env(SQUARE, max_steps=7).episode.max_steps == 7


def test_actions_are_checked():
    vec = learn.vector_env(SQUARE, message_size=1, message_range=(0, 3))
    vec.reset(seed=1)
    n = vec.num_envs
    with pytest.raises(ValueError, match="shape"):
        vec.step(np.zeros(n, dtype=np.int64))
    with pytest.raises(ValueError, match="move"):
        vec.step(np.column_stack([np.full(n, 5), np.zeros(n, int)]))
    with pytest.raises(ValueError, match="message_range"):
        vec.step(np.column_stack([np.zeros(n, int), np.full(n, 4)]))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"strategy": "optimal"}, "strategy is not an environment option"),
        ({"seed": 1}, "reset"),
        ({"cells": 4}, "cells applies to an image"),
        ({"colour": 1}, "colour is not a run setting"),
        ({"options": {"order": "random"}}, "order is an option of paper, not of"),
        ({"options": {"message_size": 99}}, "message_size must be a whole number from 0 to 64"),
        ({"message_range": (3, 1)}, "message_range"),
    ],
)
def test_options_that_do_not_apply_are_refused(options, message):
    with pytest.raises(InputError, match=message):
        learn.parallel_env(SQUARE, **options)


def test_rgb_array_frames_and_a_human_window(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = small(render_mode="rgb_array", render_size=(320, 200))
    assert env.render() is None  # nothing to draw before the first reset
    env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (200, 320, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 2
    window = learn.vector_env(SQUARE, render_mode="human", render_size=(160, 100))
    window.reset(seed=1)
    window.step(np.zeros(window.num_envs, dtype=np.int64))
    assert window.render() is None
    window.close()
    with pytest.raises(ValueError, match="render_mode"):
        small(render_mode="ascii")


def test_the_batched_interface_takes_one_array_per_step():
    vec = learn.vector_env("shapes/star.png", cells=8, message_size=3)
    obs, infos = vec.reset(seed=1)
    assert obs.shape == (vec.num_envs, vec.single_observation_space.shape[0])
    assert obs.dtype == np.float32 and infos == {}
    assert vec.action_space.shape == (vec.num_envs, 4)
    layout = vec.episode.layout
    assert len(layout.names) == layout.size == obs.shape[1]
    assert layout.names[: len(OWN)] == [
        "ready", "cruising", "heading", "progress", "moved_x", "moved_y", "number", "group",
        "step",
    ]  # fmt: skip
    assert (layout.slots(obs)[:, :, 0] <= 1).all()


def test_memory_slots_of_a_program_are_not_needed_by_the_relay():
    relay = learn.Relay(learn.Relay.Options(message_size=2))
    assert relay.memory == {} and relay.message_size == 2
    moves, messages = np.zeros(3, np.int64), np.zeros((3, 2), np.int64)
    relay.give(moves, messages)
    assert relay.act(None, Memory({}, 3), np.random.default_rng()) == (moves, messages)


FAULTS = [{"step": 3, "kind": "remove", "amount": 3}, {"step": 5, "kind": "stall", "amount": 2}]


def test_robots_a_fault_takes_terminate_and_leave_and_the_api_tests_still_pass():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(small(faults=FAULTS, failure_rate=0.01), num_cycles=100)
    env = small(faults=FAULTS)
    env.reset(seed=2)
    for _ in range(6):  # an event at step 5 strikes as the sixth step starts
        _, _, terminations, _, _ = env.step({})
    assert sum(terminations.values()) == 2 and len(terminations) == 9 - 3
    assert len(env.agents) == 9 - 3 - 2
    gone = set(env.possible_agents) - set(env.agents)
    state = env.episode.swarm.state
    fallen = np.flatnonzero((state == LOST) | (state == STALLED))
    assert gone == {f"robot_{i}" for i in fallen}
    vec = learn.vector_env(SQUARE, max_steps=30, faults=FAULTS)
    vec.reset(seed=2)
    for _ in range(6):
        _, _, _, _, infos = vec.step(np.zeros(vec.num_envs, np.int64))
    assert infos["acting"].sum() == 9 - 3 - 2


def test_the_reward_follows_a_shape_a_fault_re_formed_smaller():
    world = build_world([GroupSpec("g", Shape(SQUARE), (1, 2, 3), 9)])
    swarm = Swarm(world, create("optimal"), 1, Params(on_loss="rescale"))
    reward = learn.CoverageShare()
    reward.reset(swarm)
    Runner(swarm, max_steps=500).finish()
    assert reward(swarm).sum() == pytest.approx(1.0)  # every cell filled
    swarm.fail(np.arange(5))  # too few left: the shape is re-formed with fewer cells
    assert len(swarm.world.targets) < 9
    assert reward(swarm).shape == (9,)


@pytest.mark.parametrize("make", [learn.vector_env, learn.parallel_env])
def test_an_empty_grid_is_one_clear_error_not_an_index_error(make):
    """Issue 29, case 12: an all-empty grid with agents=1 raised an IndexError at reset."""
    with pytest.raises(InputError, match="its shape has no cells"):
        make(np.zeros((3, 3), dtype=bool), agents=1).reset(seed=0)


@pytest.mark.parametrize("make", [learn.vector_env, learn.parallel_env])
@pytest.mark.parametrize("shape", ["file", "grid"])
def test_a_packed_start_is_a_layout_not_a_file(make, shape, shapes):
    """Issue 29, case 14: start="packed" said "packed: no such file"."""
    grid = np.ones((3, 4), dtype=bool)
    env = make(str(shapes / "line.png") if shape == "file" else grid, start="packed")
    env.reset(seed=0)
    swarm = (env.episode if hasattr(env, "episode") else env.unwrapped.episode).swarm
    seeds = swarm.world.seeds
    near = np.abs(swarm.cell[:, None, :] - seeds[None, :, :]).sum(axis=2).min(axis=1)
    assert near.max() <= swarm.world.agents  # a block against the seeds, not scattered


@pytest.mark.parametrize("action", [1.9, "3", True, np.float32(2.0), [1, 2], None])
def test_parallel_env_takes_whole_numbers_only_as_vector_env_does(action):
    """Issue 29, case 14: parallel_env took 1.9 as 1 and "3" as 3, where vector_env refused
    them."""
    env = learn.parallel_env(np.ones((2, 3), dtype=bool))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="an action is a whole number"):
        env.step({env.agents[0]: action})
    with pytest.raises(ValueError, match="no agent 'robot_99999'"):
        env.step({"robot_99999": 1})
    env.step({agent: np.int64(1) for agent in env.agents})  # numpy integers are fine

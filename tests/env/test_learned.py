"""The learned baseline: deterministic per seed, its features each robot's own (so its size
does not depend on the swarm's), its weights trained on shapes the suite never tests, and
better than random on a task it never trained on."""

from __future__ import annotations

import json

import numpy as np
import pytest

from swarmshape.env.benchmark import TASKS, Learned, Random, Task, evaluate, to_json
from swarmshape.env.benchmark.learned import MOVE_FEATURES, PARAMETERS, WEIGHTS, Sight
from swarmshape.env.benchmark.score import environment

SMALL = Task("small-star", "star.png", 40, 300, (0, 1))
NOISY = Task("small-noisy", "star.png", 40, 300, (0,), distance_noise=0.1, msg_loss=0.1)


def test_the_same_seed_gives_the_same_bytes():
    learned = [to_json(evaluate(Learned(), [NOISY], seeds=[2])) for _ in range(2)]
    assert learned[0] == learned[1]


def test_the_learned_policy_beats_random_on_a_task_it_never_trained_on():
    random = evaluate(Random(), [SMALL])["tasks"][SMALL.name]
    learned = evaluate(Learned(), [SMALL])["tasks"][SMALL.name]
    assert learned["coverage"] > random["coverage"] + 0.5


def test_the_learned_features_are_each_robots_own():
    """A robot's features come from its own observation row (and its own memory) alone, so
    they are the same whichever other robots share the batch: the policy's size does not
    depend on the swarm's."""
    env = environment(Learned(), SMALL)
    obs, _ = env.reset(seed=1)
    some = np.arange(0, env.num_envs, 3)
    robots = [Sight(env.layout, env.blueprint, count) for count in (env.num_envs, len(some))]
    for _ in range(30):
        robots[0].update(obs)
        robots[1].update(obs[some])
        whole, part = robots[0].move_features(), robots[1].move_features()
        assert whole.shape == (env.num_envs, 4, len(MOVE_FEATURES))
        assert np.array_equal(whole[some], part)
        actions = np.column_stack([np.full(env.num_envs, 1), robots[0].message()])
        obs, *_ = env.step(actions)


def test_the_saved_weights_are_complete_and_trained_on_shapes_the_suite_never_tests():
    assert Learned().weights.shape == (len(WEIGHTS),)
    with pytest.raises(ValueError, match="weights"):
        Learned(np.zeros(3))
    trained = json.loads(PARAMETERS.read_text())["trained"]
    assert trained["robots"] <= 100
    tested = {task.shape.removesuffix(".png") for task in TASKS.values()}
    assert not any(name.removeprefix("train-") in tested for name in trained["tasks"])

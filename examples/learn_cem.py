"""Train a tiny controller with plain numpy: a linear policy over a few features of each
robot's observation, improved by the cross-entropy method, on a small shape.

    python examples/learn_cem.py        (needs the learn extra; about 10 s)

One shared policy drives every robot through the batched interface (one array per step).
A candidate's score is the sum of every robot's reward over an episode, which with the default
reward is the coverage the swarm reaches. The features: whether the robot hears a seed, where
it then is in the seed frame (the seed's cell less the sensed offset: a robot localising), the
mean offset of the robots around it, how many there are, and its own motion (at rest, or
cruising in one of four directions: a robot under way goes on only if the policy says
straight on again).
"""

import numpy as np

from swarmshape.env import vector_env
from swarmshape.env.observe import CRUISING, DX, DY, FRAME_X, FRAME_Y, HEADING, PRESENT, READY, SEED

STEPS = 80
env = vector_env(np.ones((3, 4), dtype=bool), max_steps=STEPS)
layout = env.layout


def features(obs: np.ndarray) -> np.ndarray:
    """Per robot ``(n, 13)``: a bias, hears a seed, its frame cell if it does (else 0, 0), the
    mean offset of the robots around it, their number / 8, at rest, cruising, its heading."""
    slots = layout.slots(obs)
    seed = slots[:, :, SEED] > 0
    hears = seed.any(axis=1)
    nearest = slots[np.arange(len(obs)), seed.argmax(axis=1)]
    where = np.where(hears[:, None], nearest[:, [FRAME_X, FRAME_Y]] - nearest[:, [DX, DY]], 0.0)
    robots = (slots[:, :, PRESENT] > 0) & ~seed
    count = robots.sum(axis=1)
    around = (slots[:, :, [DX, DY]] * robots[:, :, None]).sum(axis=1)
    around /= np.maximum(count, 1)[:, None]
    own = layout.own(obs)
    heading = own[:, HEADING, None] == np.arange(1, 5)
    motion = np.column_stack([own[:, READY], own[:, CRUISING], heading])
    return np.column_stack([np.ones(len(obs)), hears, where, around, count / 8, motion])


def score(weights: np.ndarray, seed: int = 11) -> float:
    """One episode with the policy ``argmax(weights @ features)``: the sum of all rewards."""
    obs, _ = env.reset(seed=seed)
    total = 0.0
    for _ in range(STEPS):
        obs, rewards, terminated, truncated, _ = env.step((features(obs) @ weights.T).argmax(1))
        total += rewards.sum()
        if terminated[0] or truncated[0]:
            break
    return total


rng = np.random.default_rng(0)
shape = (5, features(env.reset(seed=0)[0]).shape[1])  # 5 moves x features
mean, spread = np.zeros(shape), np.ones(shape)
before = score(mean + rng.normal(0, 1e-3, shape))
print(f"coverage with the untrained policy: {before:.0%}")
for generation in range(12):
    candidates = mean + spread * rng.normal(size=(12, *shape))
    scores = np.array([score(w) for w in candidates])
    elite = candidates[np.argsort(scores)[-3:]]
    mean, spread = elite.mean(axis=0), elite.std(axis=0) + 0.05
    print(f"generation {generation}: mean {scores.mean():.0%}, best {scores.max():.0%}")
after = score(mean)
print(f"coverage with the trained policy: {after:.0%} (from {before:.0%})")
fresh = [score(mean, seed) for seed in (12, 13, 14)]
print(f"on three new episodes: {', '.join(f'{value:.0%}' for value in fresh)}")

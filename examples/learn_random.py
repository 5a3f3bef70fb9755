"""A random policy in the PettingZoo environment: every robot is an agent.

python examples/learn_random.py        (needs the learn extra: pip install 'swarmshape[learn]')
"""

import os
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # frames without a screen

from swarmshape.env import parallel_env

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

env = parallel_env(SHAPES / "star.png", cells=8, max_steps=200, render_mode="rgb_array")
observations, infos = env.reset(seed=1)
env.action_space("robot_0").seed(1)  # one space shared by every robot: seeded once
rewards_total = 0.0
while env.agents:
    actions = {agent: env.action_space(agent).sample() for agent in env.agents}
    observations, rewards, terminations, truncations, infos = env.step(actions)
    rewards_total += sum(rewards.values())
frame = env.render()
env.close()
size = env.observation_space("robot_0").shape[0]
print(f"{len(env.possible_agents)} robots, each observing {size} numbers")
total = round(rewards_total, 9) + 0  # the sum of floats, without a "-0.000"
print(f"after 200 random steps: coverage {env.coverage():.0%}, rewards sum {total:.3f}")
print(f"a frame of shape {frame.shape}")

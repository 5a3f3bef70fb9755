"""A built-in local program, local-swap, driven through the environment: the policy sees only
the observations, turns them back into the `Perception` the program expects, and forms the
shape. Proof that an observation carries everything a robot's program senses.

    python examples/learn_scripted.py        (needs the learn extra)

The policy keeps the program's memory between steps (a policy with state, as a recurrent one
would) and draws its random choices from its own generator, so the run differs in detail from
``swarmshape run --strategy local-swap``, but not in what the robots know.
"""

from pathlib import Path

import numpy as np

from swarmshape import strategies
from swarmshape.core.local import Memory
from swarmshape.env import perception_of, vector_env

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

program = strategies.create("local-swap")
env = vector_env(
    SHAPES / "star.png",
    cells=6,
    max_steps=5_000,
    message_size=program.message_size,  # the program's broadcast: cells, goals, robot numbers
    message_range=(-1024, 1023),
)
obs, _ = env.reset(seed=1)
memory = Memory(program.memory, env.num_envs)
rng = np.random.default_rng(1)
terminated = truncated = np.zeros(env.num_envs, dtype=bool)
while not (terminated.any() or truncated.any()):
    sense = perception_of(obs, env.layout, env.blueprint)
    moves, messages = program.act(sense, memory, rng)
    obs, rewards, terminated, truncated, _ = env.step(np.column_stack([moves, messages]))
steps = env.episode.swarm.step_count
print(f"local-swap through the environment: {env.num_envs} robots, {steps} steps")
print(f"shape formed: {bool(terminated.all())}, coverage {env.coverage():.0%}")

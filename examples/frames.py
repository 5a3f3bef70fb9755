"""Frames of a run as numpy RGB arrays, without a window: for notebooks and your own plots.

    python examples/frames.py

In a notebook, show a frame with ``PIL.Image.fromarray(frame)`` or ``plt.imshow(frame)``.
"""

import os
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # no screen needed

import swarmshape
from swarmshape.ui.render import frame

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

config = swarmshape.configure(SHAPES / "horseshoe.png", seed=3)
runner = swarmshape.Runner(swarmshape.build(config), max_steps=config.max_steps)
frames = [frame(runner.swarm, size=(320, 200))]
while not runner.finished:
    runner.step()
    if runner.swarm.step_count % 25 == 0:
        frames.append(frame(runner.swarm, size=(320, 200)))
frames.append(frame(runner.swarm, size=(320, 200)))
print(f"{len(frames)} frames of shape {frames[0].shape} and dtype {frames[0].dtype}")
print(f"the last one has {len(set(map(tuple, frames[-1].reshape(-1, 3))))} colours")

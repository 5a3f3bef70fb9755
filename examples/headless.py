"""Build a run from code, run it headless, and print its metrics.

python examples/headless.py
"""

from pathlib import Path

import swarmshape

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

config = swarmshape.configure(SHAPES / "star.png", seed=1, cells=20, strategy="optimal")
swarm = swarmshape.build(config)
swarmshape.run(swarm, max_steps=config.max_steps)
metrics = swarmshape.run_metrics(swarm)
print(f"{metrics['shape']}: {metrics['agents']} robots formed it in {metrics['steps']} steps")
print(f"coverage {metrics['coverage']:.0%}, {metrics['makespan_ratio']:.2f}x the lower bound")

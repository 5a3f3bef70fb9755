"""A strategy of your own: each target, in order, takes the nearest free robot.

    python examples/my_strategy.py

checks it against the invariants every strategy must keep, then forms the star with it. From
the command line the same class runs as ``--strategy examples/my_strategy.py:NearestFirst``.
"""

from pathlib import Path

import numpy as np

import swarmshape
from swarmshape import Strategy, register


@register
class NearestFirst(Strategy):
    name = "nearest-first"
    description = "targets in order, each takes the nearest free robot of its group"

    def on_start(self, swarm):
        free = np.ones(len(swarm.cells), dtype=bool)
        for target, cell in enumerate(swarm.targets):
            mine = free & (swarm.group == swarm.target_group[target])
            distance = np.abs(swarm.cells - cell).sum(axis=1)
            robot = np.flatnonzero(mine)[np.argmin(distance[mine])]
            free[robot] = False
            swarm.assign(np.array([robot]), np.array([target]))


if __name__ == "__main__":
    print(swarmshape.check_strategy(NearestFirst, runs=5).text())
    star = Path(__file__).resolve().parent.parent / "shapes" / "star.png"
    config = swarmshape.configure(star, seed=1, cells=20, strategy="nearest-first")
    swarm = swarmshape.run(swarmshape.build(config), max_steps=config.max_steps)
    print(f"star formed in {swarm.completed_at[0]} steps by {len(swarm.cell)} robots")

"""A local program in a few lines: robots gather round the seeds by a hop-count gradient, each
knowing only its neighbours (the README's "Writing a local program"). Run it:
``python examples/my_program.py`` (it checks the run and prints how close the robots came)."""

from pathlib import Path
from typing import ClassVar

import numpy as np

from swarmshape import Program, Slot, register


@register
class Gather(Program):
    name = "gather"
    description = "walk down the hop count to the seeds; stop on touching a robot that has"
    message_size = 1
    memory: ClassVar[dict[str, Slot]] = {"hops": Slot(np.int64, 999), "state": Slot(np.int64)}
    states = ("resting", "heading in", "lost")  # the viewer colours robots by memory.state
    shown = "hops"  # and prints this slot on them (key g)

    def act(self, sense, memory, rng):
        heard = np.where(sense.seed, -1, np.where(sense.heard, sense.message[:, 0], 999))
        nearest = np.full(len(sense), 999)
        np.minimum.at(nearest, sense.owner, heard)  # the lowest hop count heard
        memory.hops = np.where(nearest < 30, nearest + 1, 999)  # 30 hops: lost, not counting up
        moves = np.zeros(len(sense), dtype=np.int64)
        lower = heard < memory.hops[sense.owner]  # a neighbour nearer the seeds
        far = np.abs(sense.offset).sum(axis=1) > 1.5  # and not touching already
        step = np.where(
            np.abs(sense.offset[:, 0]) >= np.abs(sense.offset[:, 1]),
            np.where(sense.offset[:, 0] > 0, 1, 2),
            np.where(sense.offset[:, 1] > 0, 3, 4),
        )
        toward = np.flatnonzero(lower & far)
        moves[sense.owner[toward]] = step[toward]
        wander = (nearest >= 999) & (rng.random(len(sense)) < 0.5)  # lost: look around
        moves[wander] = rng.integers(1, 5, wander.sum())
        memory.state = np.where(nearest >= 999, 2, np.where(moves > 0, 1, 0))
        return moves, memory.hops[:, None]


if __name__ == "__main__":
    import swarmshape

    shape = Path(__file__).resolve().parent.parent / "shapes" / "small-square.png"
    config = swarmshape.configure(shape, strategy="gather", seed=1, max_steps=1500)
    swarm = swarmshape.build(config)

    def apart() -> float:
        """Mean lattice distance from each robot to its nearest seed."""
        to_seeds = np.abs(swarm.cell[:, None, :] - swarm.world.seeds[None, :, :]).sum(axis=2)
        return float(to_seeds.min(axis=1).mean())

    before = apart()
    swarmshape.run(swarm, max_steps=config.max_steps)
    print(f"robots came from {before:.1f} to {apart():.1f} cells from a seed on average")
    assert apart() < before and swarm.overlap_total == 0

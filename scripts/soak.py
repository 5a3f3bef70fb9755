"""Soak test: a long run with wandering spare robots and live shape changes, checking
invariants as it goes and that memory stays flat. Not part of the test suite.

    .venv/bin/python scripts/soak.py [--steps 1000000] [--strategy optimal] [--every 20000]
    .venv/bin/python scripts/soak.py --failure-rate 2e-6 --spares 150    # fault mode

Fault mode adds a steady failure rate (each robot removed with that chance per step) and a
supply of spare robots; a live shape change then asks for the shape at the largest scale the
robots left can fill, and the report says how many faults struck and how many healed.
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

from swarmshape.config import RunConfig
from swarmshape.core.audit import overlapping_pairs
from swarmshape.core.shape import Shape
from swarmshape.core.states import STALLED
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.io.bitmap import load_grid
from swarmshape.runs import start_swarm

SHAPES = Path(__file__).resolve().parent.parent / "shapes"


def resident_mb() -> float:
    """Current resident memory of this process (Linux /proc), in MB."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * resource.getpagesize() / 2**20


def violations(swarm: Swarm) -> list[str]:
    found = []
    pos = swarm.positions()[swarm.present]
    width, height = swarm.world.size
    if not np.isfinite(pos).all():
        found.append("non-finite position")
    if (pos < 0.5).any() or (pos[:, 0] > width - 0.5).any() or (pos[:, 1] > height - 0.5).any():
        found.append("left the arena")
    if len(overlapping_pairs(np.concatenate([pos, swarm.world.seeds + 0.5]))[0]):
        found.append("overlap")
    if swarm.present.sum() + swarm.faults.lost != swarm.world.agents:
        found.append("robots not conserved (present + removed != agents)")
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--strategy", default="optimal")
    parser.add_argument("--every", type=int, default=20_000, help="steps between shape changes")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--failure-rate", type=float, default=0.0, help="fault mode: P per step")
    parser.add_argument("--spares", type=int, default=30, help="robots beyond the largest shape")
    args = parser.parse_args()

    shapes = [Shape(load_grid(SHAPES / name)) for name in ("horseshoe.png", "square.png")]
    agents = max(s.count for s in shapes) + args.spares  # spare robots that wander
    world = build_world([GroupSpec("soak", shapes[0], (58, 111, 216), agents)])
    config = RunConfig(strategy=args.strategy, seed=args.seed, failure_rate=args.failure_rate)
    swarm = start_swarm(config, world)
    started, broken, changes, reformed = time.perf_counter(), [], 0, []
    memory = {}
    while swarm.step_count < args.steps:
        swarm.step()
        if swarm.step_count == 10_000:
            memory["after warm-up"] = resident_mb()
        if swarm.step_count % 1000 == 0:
            broken += [f"step {swarm.step_count}: {v}" for v in violations(swarm)]
        if swarm.step_count % args.every == 0:
            reformed.append(swarm.complete)
            changes += 1
            mobile = int((swarm.present & (swarm.state != STALLED)).sum())
            if mobile == 0:
                break
            swarm.reshape(0, shapes[changes % 2].fitted(mobile))
    memory["at the end"] = resident_mb()
    seconds = time.perf_counter() - started
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(
        f"steps {swarm.step_count:,} in {seconds:.0f} s ({swarm.step_count / seconds:,.0f} steps/s)"
    )
    print(f"strategy {args.strategy}, {agents} agents, {changes} live shape changes")
    print(f"shape complete before {sum(reformed)} of {len(reformed)} changes")
    for when, mb in memory.items():
        print(f"resident memory {when}: {mb:.1f} MB")
    print(f"peak resident memory: {peak:.1f} MB")
    print(f"overlaps counted: {swarm.overlap_total}; invariant violations: {len(broken)}")
    log = swarm.faults.log
    if log:
        healed = [f["recovery_steps"] for f in log if f["recovery_steps"] is not None]
        print(
            f"faults: {len(log)} struck, {swarm.faults.lost} robots removed, {len(healed)} "
            f"healed (slowest {max(healed, default=0)} steps, mean "
            f"{np.mean(healed) if healed else 0:.0f}); unhealed at the end: "
            f"{len(log) - len(healed)}; final scale {swarm.world.groups[0].shape.scale:.2f}, "
            f"{len(swarm.world.targets)} cells, {int(swarm.present.sum())} robots left"
        )
    for line in broken[:10]:
        print("  " + line)


if __name__ == "__main__":
    main()

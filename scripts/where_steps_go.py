"""Where a local program's robot-steps go: each step of each robot not yet finished, counted by
what the robot was doing, up to the step a share of the robots had finished and after it.

python scripts/where_steps_go.py shapes/letter-s.png --strategy local-swap --cells 14 --seeds 6

A robot counts until its program calls it finished (`Program.finished`; for a program that
does not say, until it settles), each step as one of: *without bearings* (`Program.estimate`
says it does not know where it is), *under way* (between two cells), *starting off* (at rest,
and under way after the step), or *standing* (at rest, and still at rest after it: it asked
for nothing, or its claim failed). The bulk is up to the step at which `--share` of the
robots had finished, the tail the rest of the run. Stop-and-go shows as starting off, a slow
spread of bearings as steps without them, queues and trades waited for as standing.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

import swarmshape
from swarmshape.core.local import LocalControl
from swarmshape.core.states import SETTLED
from swarmshape.errors import InputError
from swarmshape.runs import Runner

KINDS = ("without bearings", "under way", "starting off", "standing")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("shape", type=Path)
    parser.add_argument("--strategy", default="local-swap", help="a local program")
    parser.add_argument("--cells", type=int)
    parser.add_argument("--agents", type=int)
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0 up (default 3)")
    parser.add_argument("--max-steps", type=int, default=50_000)
    parser.add_argument("--share", type=float, default=0.9, help="where the bulk ends (0.9)")
    args = parser.parse_args()
    if not 0 < args.share <= 1 or args.seeds < 1:
        print("where_steps_go.py: error: --share is in (0, 1], --seeds at least 1", file=sys.stderr)
        return 2
    phases: dict[str, Counter[str]] = {"bulk": Counter(), "tail": Counter()}
    seed = 0
    try:
        for seed in range(args.seeds):
            config = swarmshape.configure(
                args.shape, seed=seed, strategy=args.strategy, cells=args.cells,
                agents=args.agents, max_steps=args.max_steps,
            )  # fmt: skip
            swarm = swarmshape.build(config)
            if not isinstance(swarm.driver, LocalControl):
                raise InputError(f"{args.strategy} is central: this counts local programs' steps")
            steps, bulk = count(swarm, args.max_steps, args.share, phases)
            print(f"seed {seed}: {args.share:.0%} finished at step {_step(bulk)}, all at"
                  f" {_step(steps)}")  # fmt: skip
    except InputError as error:
        print(f"where_steps_go.py: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl+C: the steps counted so far
        _table(phases, f"seeds 0 to {seed}, stopped in seed {seed}")
        return 130
    _table(phases, f"seeds 0 to {args.seeds - 1}")
    return 0


def _table(phases: dict[str, Counter[str]], runs: str) -> None:
    print(f"\nrobot-steps of robots not yet finished, {runs}")
    print(f"{'':18}" + "".join(f"{phase:>18}" for phase in phases))
    for kind in KINDS:
        cells = []
        for tally in phases.values():
            whole = sum(tally.values()) or 1
            cells.append(f"{tally[kind]:>10,} {tally[kind] / whole:6.1%}")
        print(f"{kind:18}" + "".join(f"{cell:>18}" for cell in cells))


def count(
    swarm: swarmshape.Swarm, max_steps: int, share: float, phases: dict[str, Counter[str]]
) -> tuple[int | None, int | None]:
    """Step `swarm` until it finishes, adding its robot-steps to `phases`; the step at which it
    finished (None: it did not) and the step at which `share` of its robots had."""
    program, memory = swarm.driver.program, swarm.driver.memory
    runner = Runner(swarm, [], max_steps=max_steps)
    bulk_end = None
    while not runner.finished:
        said = program.finished(memory)
        done = swarm.state == SETTLED if said is None else said
        if bulk_end is None and done.mean() >= share:
            bulk_end = swarm.step_count
        estimate = program.estimate(memory)
        lost = ~estimate[0] if estimate is not None else np.zeros(len(done), dtype=bool)
        under_way = swarm.ahead > 0
        cell = swarm.cell.copy()
        runner.step()
        started = ~under_way & ((swarm.ahead > 0) | (swarm.cell != cell).any(axis=1))
        kind = np.select([lost, under_way, started], [0, 1, 2], default=3)
        tally = phases["bulk" if bulk_end is None else "tail"]
        for index, name in enumerate(KINDS):
            tally[name] += int(((kind == index) & ~done).sum())
    return swarm.step_count if swarm.complete else None, bulk_end


def _step(step: int | None) -> str:
    return "(never)" if step is None else f"{step:,}"


if __name__ == "__main__":
    sys.exit(main())

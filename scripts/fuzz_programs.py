"""Fuzz a strategy (a local program, above all) on random shapes with holes and separate
pieces, under noise, lost messages and faults: what `swarmshape check` does on small shapes
with perfect senses, on harder cases. Not part of the test suite: a case takes seconds to a
minute.

    .venv/bin/python scripts/fuzz_programs.py mean-shift --cases 120
    .venv/bin/python scripts/fuzz_programs.py local-swap --first 92 --cases 1   # one case again

Case N draws everything from a generator seeded with N: a shape of up to 12 x 12 cells (each
cell ink with one chance for the whole shape, so some are solid and some lace; for a program
that grows from the seeds, the part of it such a swarm can form, `Shape.solid`), robots from
two fewer to nine more than its cells, on half the cases message loss and distance noise of
0.1, on two in five a remove or a stall of 5 to 30 % of the robots at a step up to 400. Each
run is watched as `swarmshape check` watches one (every invariant, a step within
`--step-seconds`), and is saved and resumed on the way. One line per case with a problem
(not formed counts as one, but for a program that grows from its seeds, which does not repair,
a run with faults need only end); the exit status is 1 if any case has one.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from swarmshape import strategies
from swarmshape.check import RESUME_AT, watch_run
from swarmshape.config import RunConfig
from swarmshape.core.faults import FaultEvent, Faults
from swarmshape.core.guard import PluginCode
from swarmshape.core.shape import Shape
from swarmshape.core.steering import Strategy
from swarmshape.core.world import GroupSpec, build_world
from swarmshape.errors import InputError


def case(cls: type[Strategy], number: int, max_steps: int, step_seconds: float) -> str | None:
    """Case `number` run once under the watch: what went wrong, or None."""
    rng = np.random.default_rng(number)
    height, width = rng.integers(3, 13, size=2)
    grid = rng.random((height, width)) < rng.uniform(0.4, 0.95)
    grid[rng.integers(height), rng.integers(width)] = True
    # only what a program that grows from the seeds can form, as `swarmshape check` draws
    shape = Shape(grid).solid() if getattr(cls, "grows_from_seeds", False) else Shape(grid)
    agents = max(1, shape.count + int(rng.integers(-2, 10)))
    world = build_world([GroupSpec("fuzz", shape, (1, 2, 3), agents)])
    noise = 0.1 if rng.random() < 0.5 else 0.0
    events: tuple[FaultEvent, ...] = ()
    if rng.random() < 0.4:
        step = int(rng.integers(0, 400))
        kind = str(rng.choice(["remove", "stall"]))
        events = (FaultEvent(step, kind, float(rng.uniform(0.05, 0.3))),)
    seed = int(rng.integers(2**31))
    # the command line's physics, with the case's senses
    params = RunConfig(msg_loss=noise, distance_noise=noise).params()
    # a program that grows from its seeds does not repair (see test_faults.py): after a fault
    # its run may end unformed, but it must end
    repairs = not events or not getattr(cls, "grows_from_seeds", False)
    watch = watch_run(
        world, cls, seed, max_steps, step_seconds, RESUME_AT, params, Faults(events), repairs
    )
    if not watch.problems:
        return None
    what = f"{shape.count} cells, {agents} robots, noise {noise:g}, faults {list(events)}"
    return f"case {number} ({what}, seed {seed}): {watch.problems[0]}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("strategy")
    parser.add_argument("--cases", type=int, default=100)
    parser.add_argument("--first", type=int, default=0, help="the first case's number")
    parser.add_argument("--max-steps", type=int, default=15_000)
    parser.add_argument("--step-seconds", type=float, default=5.0)
    args = parser.parse_args()
    if min(args.cases, args.max_steps, args.step_seconds) <= 0:
        parser.error("--cases, --max-steps and --step-seconds must be more than 0")
    try:
        with PluginCode.named(args.strategy).running(" as it was loaded"):
            cls = strategies.get(args.strategy)
    except InputError as error:
        print(f"fuzz_programs.py: error: {error}", file=sys.stderr)
        return 2
    found = done = 0
    try:
        for number in range(args.first, args.first + args.cases):
            problem = case(cls, number, args.max_steps, args.step_seconds)
            done += 1
            if problem:
                found += 1
                print(problem, flush=True)
    except KeyboardInterrupt:  # Ctrl+C: say what the cases run so far found
        print(f"{args.strategy}: stopped in case {args.first + done}, {done} cases, {found} "
              "with a problem")  # fmt: skip
        return 130
    print(f"{args.strategy}: {done} cases, {found} with a problem")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())

"""Check any strategy against the invariants every run must keep, and say in plain words what
broke: ``check_strategy("optimal")`` or ``swarmshape check my_strategies.py:Mine``.

Each random shape is run twice with the same seed. At every step the robots' squares must not
overlap (seeds included), stay in the arena, keep their number (robots are conserved except
those a fault removed), and settled robots must stay where they are; the two runs must be
identical step by step (randomness from anywhere but ``swarm.rng`` shows up here; the second
is saved to a state file and resumed at step `RESUME_AT`, so a strategy whose state does not
survive that shows up too); and the
shape must form within the step limit and stay formed for `AFTER_FORMED` steps more (unless a
fault opened it again). A failure of the strategy's own code (an exception, a write to its
read-only view, a robot that does not exist, ``sys.exit``) and a step that takes over
`STEP_SECONDS` (a loop) are problems too, said in plain words; the check stops at the first.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import signal
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TypeVar

import numpy as np

from swarmshape import strategies
from swarmshape.core import compiled
from swarmshape.core.audit import overlapping_pairs
from swarmshape.core.faults import Faults
from swarmshape.core.guard import PluginCode
from swarmshape.core.shape import Shape
from swarmshape.core.snapshot import Snapshot, SnapshotError, prefixed
from swarmshape.core.states import SETTLED
from swarmshape.core.steering import Strategy
from swarmshape.core.swarm import Params, Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.errors import PluginError, Stopped
from swarmshape.io.checkpoint import load_state, save_state
from swarmshape.runs import Observer, Runner

T = TypeVar("T")

AFTER_FORMED = 50
"""Steps a formed shape is watched for, with its spare robots wandering."""
STEP_SECONDS = 10.0
"""How long one step may take. The check's shapes have a few dozen robots, and the built-in
strategies step them in a millisecond or two on a busy machine: a strategy that takes this long
is caught in a loop."""


RESUME_AT = 5
"""The step at which the second run of each shape is saved and resumed (its strategy has set
up whatever it keeps in ``on_start`` by then, and most of the run is still to come)."""


class StepTooLong(Stopped):
    """A step ran past `STEP_SECONDS`."""


class InvariantWatch(Observer):
    """An observer that notes, in words, every invariant a run breaks, and fingerprints each
    step so that two runs can be compared."""

    def __init__(self, limit: int = 5) -> None:
        self.problems: list[str] = []
        self.limit = limit
        """Problems kept per run; the first few say enough."""
        self.digest = hashlib.sha256()
        self._cells: np.ndarray | None = None
        self._settled: np.ndarray | None = None
        self._formed = False
        self._faults = 0
        self.failed = False
        """The run stopped short (see `fail`)."""
        self._step = -1

    def capture(self, swarm: Swarm) -> None:
        step = swarm.step_count
        if step == self._step:  # seen already (a resumed run is shown again)
            return
        self._step = step
        present = swarm.present
        pos = swarm.positions()[present]
        width, height = swarm.world.size
        if not (np.isfinite(pos).all() and np.isfinite(swarm.speed).all()):
            self._note(f"step {step}: a position or speed is not a finite number")
        elif (
            (pos < 0.5).any() or (pos[:, 0] > width - 0.5).any() or (pos[:, 1] > height - 0.5).any()
        ):
            outside = ((pos < 0.5) | (pos > (width - 0.5, height - 0.5))).any(1)
            robot = int(np.flatnonzero(present)[np.flatnonzero(outside)[0]])
            self._note(f"step {step}: robot {robot} left the {width}x{height} arena")
        everything = np.concatenate([pos, swarm.world.seeds + 0.5])
        i, j = overlapping_pairs(everything)
        if len(i):
            ids = np.flatnonzero(present)
            first, second = _name(i[0], ids), _name(j[0], ids)
            self._note(f"step {step}: {first} and {second} overlap")
        removed = sum(f["robots"] for f in swarm.faults.log if f["kind"] != "stall")
        if len(pos) + removed != swarm.world.agents or swarm.faults.lost != removed:
            self._note(
                f"step {step}: {len(pos)} robots where there were {swarm.world.agents} "
                f"and faults removed {removed}"
            )
        if len(swarm.faults.log) != self._faults:  # a fault may open cells of a formed shape
            self._faults, self._formed = len(swarm.faults.log), False
        if self._settled is not None:
            still = self._settled & (swarm.state == SETTLED)
            moved = np.flatnonzero(still & (swarm.cell != self._cells).any(axis=1))
            if len(moved):
                self._note(f"step {step}: robot {moved[0]} moved while settled")
        if self._formed and not swarm.complete:
            self._note(f"step {step}: the formed shape lost a cell without any change to it")
        self._formed |= swarm.complete
        self._cells, self._settled = swarm.cell.copy(), swarm.state == SETTLED
        self.digest.update(np.ascontiguousarray(swarm.positions()).tobytes())
        self.digest.update(swarm.state.tobytes())

    def _note(self, problem: str) -> None:
        if len(self.problems) < self.limit:
            self.problems.append(problem)

    def fail(self, problem: str) -> None:
        """The run could not go on: the strategy's code failed, or a step took too long."""
        self.problems.append(problem)
        self.failed = True


def _name(index: int, robots: np.ndarray) -> str:
    """Robot or seed number `index` of the squares checked: the robots present, then seeds."""
    return f"robot {robots[index]}" if index < len(robots) else f"seed {index - len(robots)}"


@dataclass
class Report:
    """What `check_strategy` found."""

    strategy: str
    runs: int
    problems: list[str] = field(default_factory=list)

    @property
    def clean(self) -> bool:
        return not self.problems

    def text(self) -> str:
        head = f"strategy {self.strategy!r}: {self.runs} random shapes, each run twice"
        if self.clean:
            return f"{head}: no problems found"
        count = len(self.problems)
        lines = [f"{head}: {count} problem{'' if count == 1 else 's'}"]
        return "\n".join(lines + [f"  - {problem}" for problem in self.problems])


def check_strategy(
    strategy: str | type[Strategy],
    *,
    runs: int = 20,
    seed: int = 0,
    max_steps: int = 20_000,
    step_seconds: float = STEP_SECONDS,
) -> Report:
    """Run `strategy` (a name, ``module:Class``, or a class) on `runs` small random shapes and
    report every broken invariant. Code that fails as it loads is a `PluginError`."""
    if isinstance(strategy, type):
        cls = strategy
    else:
        with PluginCode.named(strategy).running(" as it was loaded"):
            cls = strategies.get(strategy)
    report = Report(cls.name, runs)
    shapes = np.random.default_rng(seed)
    for index in range(runs):
        world = random_world(shapes, solid=getattr(cls, "grows_from_seeds", False))
        run_seed = int(shapes.integers(2**32))
        where = (
            f"shape {index} ({len(world.targets)} cells, {world.agents} robots, seed {run_seed})"
        )
        watches = []
        for resume_at in (None, RESUME_AT):
            watches.append(watch_run(world, cls, run_seed, max_steps, step_seconds, resume_at))
            if watches[-1].failed:
                report.problems += [f"{where}: {problem}" for problem in watches[-1].problems]
                return report
        for watch in watches[:1]:
            report.problems += [f"{where}: {problem}" for problem in watch.problems]
        if watches[0].digest.digest() != watches[1].digest.digest():
            report.problems.append(
                f"{where}: the same seed gave a different run (use swarm.rng for randomness)"
            )
    return report


def watch_run(
    world: World,
    cls: type[Strategy],
    seed: int,
    max_steps: int,
    step_seconds: float = STEP_SECONDS,
    resume_at: int | None = None,
    params: Params | None = None,
    faults: Faults | None = None,
    must_form: bool = True,
) -> InvariantWatch:
    """Run one strategy on `world` to the end under an `InvariantWatch`, each step (and the
    making of the swarm) within `step_seconds`, saved to a file and resumed after step
    `resume_at` if given; with the run's `params` (its senses' noise, say) and `faults` if
    given. A run that ends unformed (stranded, or at rest) is a problem if it `must_form`; one
    that runs out of steps always is: it never ends."""
    watch = InvariantWatch()
    runner: Runner | None = None
    try:
        with _time_limit(step_seconds) as limited:
            with PluginCode.of(cls).running(" as it was made"):
                plugin = strategies.create(cls)
            swarm = limited(lambda: Swarm(world, plugin, seed, params, faults=faults))
            runner = Runner(swarm, [watch], max_steps)
            while not runner.finished:
                limited(runner.step)
                if runner.swarm.step_count == resume_at:
                    resumed = limited(functools.partial(saved_and_resumed, runner.swarm, cls))
                    runner = Runner(resumed, [watch], max_steps)
            swarm = runner.swarm
            runner.close()
            coverage = f"coverage {swarm.filled.mean():.0%}"
            if not swarm.complete and runner.out_of_steps:
                watch.problems.append(f"not formed after {max_steps} steps ({coverage})")
            elif not swarm.complete and must_form:
                why = "stranded" if swarm.stranded else "at rest"
                watch.problems.append(
                    f"ended unformed at step {swarm.step_count}, {why} ({coverage})"
                )
            for _ in range(AFTER_FORMED):
                limited(runner.step)
    except PluginError as error:
        watch.fail(str(error))
    except SnapshotError as error:
        watch.fail(f"step {resume_at}: the run could not be saved and resumed: {error}")
    except StepTooLong:
        step = "its start" if runner is None else f"step {runner.swarm.step_count}"
        watch.fail(
            f"{step} took over {step_seconds:g} s (is the strategy caught in a loop?); the "
            "check stopped it"
        )
    return watch


def saved_and_resumed(swarm: Swarm, cls: type[Strategy]) -> Swarm:
    """`swarm` written to a state file and read back, by a fresh plug-in of `cls`."""
    with tempfile.TemporaryDirectory(prefix="swarmshape-check-") as folder:
        path = Path(folder) / "check.state"
        save_state(path, prefixed("swarm", swarm.snapshot()))  # as a run saves it
        saved = Snapshot(load_state(path)).part("swarm")
    return Swarm.restored(saved, strategies.create(cls))


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[Callable[[Callable[[], T]], T]]:
    """A way to run a call within `seconds`, past which it is stopped with `StepTooLong` (on
    the main thread, where signals arrive; elsewhere without a limit)."""
    if threading.current_thread() is not threading.main_thread():
        yield lambda call: call()
        return

    began = [0.0, 0.0]  # when the call began, and the seconds spent compiling by then
    running = [False]

    def stop(*_: object) -> None:
        """Stop the call, unless numba is compiling one of the project's kernels (raised in
        there, it broke numba) or did for part of the time: the timer fires again once the
        call's own time is up. A signal handled after the call ended does nothing: set again
        then, the timer outlived the limit, and its signal killed the process."""
        if not running[0] or compiled.compiling():
            return
        spent = time.perf_counter() - began[0] - (compiled.compile_seconds() - began[1])
        if spent < seconds:
            signal.setitimer(signal.ITIMER_REAL, seconds - spent, seconds)
            return
        raise StepTooLong

    def limited(call: Callable[[], T]) -> T:
        began[:] = [time.perf_counter(), compiled.compile_seconds()]
        running[0] = True
        signal.setitimer(signal.ITIMER_REAL, seconds, seconds)  # again, if it is swallowed
        try:
            return call()
        finally:
            running[0] = False
            signal.setitimer(signal.ITIMER_REAL, 0)

    previous = signal.signal(signal.SIGALRM, stop)
    try:
        yield limited
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def random_world(rng: np.random.Generator, solid: bool = False) -> World:
    """A small random shape with a few robots too many or too few, in a roomy arena (keeping
    the auto arena's margin round it, so robots can pass round the seeds); only its
    `Shape.solid` part if `solid` (for a program that grows from the seeds)."""
    height, width = rng.integers(3, 7, size=2)
    grid = rng.random((height, width)) < rng.uniform(0.3, 0.9)
    grid[rng.integers(height), rng.integers(width)] = True
    shape = Shape(grid).solid() if solid else Shape(grid)
    agents = max(1, shape.count + int(rng.integers(-3, 7)))
    spec = GroupSpec("check", shape, (58, 111, 216), agents)
    auto = build_world([spec])
    room = int(rng.integers(0, 12))
    spec = replace(spec, pose=auto.groups[0].pose)
    return build_world([spec], (auto.size[0] + room, auto.size[1] + room // 2))

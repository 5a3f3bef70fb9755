"""A run with its outputs, in a window or headless: what ``swarmshape run`` and ``edit`` do.

The outputs are checked before anything runs, observers record while it runs, and the state,
the metrics and the summary are written at the end. The command line only maps its options
onto `Outputs` and `Session` and its exit codes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarmshape import strategies
from swarmshape.config import RunConfig
from swarmshape.core.grid import resized
from swarmshape.core.guard import PluginCode
from swarmshape.core.metrics import run_metrics
from swarmshape.core.shape import Pose
from swarmshape.core.snapshot import SnapshotError
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import World, blank_world
from swarmshape.errors import InputError, Terminated
from swarmshape.experiments.positions import Positions
from swarmshape.experiments.progress import RunProgress
from swarmshape.experiments.trace import Trace
from swarmshape.io.bitmap import Picture, read_picture
from swarmshape.io.files import check_output, distinct_outputs, identity, write_text
from swarmshape.io.scenario import PALETTE, parse_colour
from swarmshape.runs import (
    Observer,
    Runner,
    files_read,
    load_world,
    resume,
    save,
    start_cells,
    start_swarm,
    strategy_file,
)

OUTPUT_OPTIONS = ("metrics", "record", "frames", "trace", "save_state", "positions")

BLANK_ARENA = (48, 30)
BLANK_POSE = Pose(4, 4)
"""The editor's empty canvas: its size and where the seeds sit."""


@dataclass(frozen=True)
class Outputs:
    """Files a run writes; existing ones are replaced only with `force`."""

    metrics: Path | None = None
    record: Path | None = None
    frames: Path | None = None
    record_every: int = 1
    record_size: tuple[int, int] | None = None
    """Frame size in pixels; None is the recorder's own default."""
    trace: Path | None = None
    trace_every: int = 1
    save_state: Path | None = None
    positions: Path | None = None
    positions_every: int = 1
    force: bool = False

    def check(
        self,
        inputs: Mapping[Path, str] | None = None,
        resumed: Path | None = None,
        others: Sequence[tuple[str, Path]] = (),
    ) -> None:
        """Fail before the run, not after it, when an output cannot be written, would replace
        one of the run's `inputs` (path: what it is to the run), would replace a file the
        user did not ask to replace (`force`; `--save-state` may replace the state `resumed`,
        which is one of the inputs: the run goes on where it was saved), or names a file the
        session writes `others`-wise (what writes it, path): the editor's drawing, say."""
        named = [(f"--{o.replace('_', '-')}", getattr(self, o)) for o in OUTPUT_OPTIONS]
        named = [(flag, path) for flag, path in named if path is not None]
        distinct_outputs([*others, *named])
        for flag, path in named:
            continues = flag == "--save-state" and resumed is not None and _same(path, resumed)
            check_output(
                path,
                flag,
                may_replace=self.force or continues,
                folder=flag == "--frames",
                inputs={
                    file: what
                    for file, what in (inputs or {}).items()
                    if not continues or not _same(file, resumed)
                },
            )

    @contextlib.contextmanager
    def observers(self) -> Iterator[list[Observer]]:
        """Recording and tracing, as asked for; discarded (their temporary files removed) if
        anything fails or stops the run before they are closed, making them included."""
        observers: list[Observer] = []
        try:
            if self.record or self.frames:
                from swarmshape.ui.record import Recorder  # draws with pygame, offscreen

                size = {} if self.record_size is None else {"size": self.record_size}
                observers.append(Recorder(self.record, self.frames, self.record_every, **size))
            if self.trace:
                observers.append(Trace(self.trace, self.trace_every))
            if self.positions:
                observers.append(Positions(self.positions, self.positions_every))
            yield observers
        except BaseException:
            for observer in observers:
                observer.discard()
            raise


@dataclass(frozen=True)
class Session:
    """One ``run`` or ``edit``: what to run (a description, or a saved state to resume), how
    (a window, the editor, or headless) and where its outputs go. A resumed run takes only
    ``max_steps`` from `config`; the rest was saved with it."""

    config: RunConfig
    outputs: Outputs
    resume: Path | None = None
    strategy: str | None = None
    """With `resume`: the strategy named on the command line, for a run saved with code."""
    window: bool = True
    editing: bool = False
    speed: float = 8

    def start(self) -> dict[str, Any] | None:
        """Run it, write its outputs, print its summary; return its metrics (None when the
        editor closed before any swarm ran)."""
        drawing = self.config.shape if self.editing and self.resume is None else None
        # the drawing may not exist yet, so it is no input to keep, but Ctrl+S writes it
        self.outputs.check(
            self._inputs(), self.resume, [("the editor's Ctrl+S", drawing)] if drawing else []
        )
        with self._loading():
            config, world, prepared = self._prepare()

        def make_swarm(on: World) -> Swarm:
            with self._loading():
                return prepared(on)

        interrupted = False
        with ended_by_signals() as watch, self.outputs.observers() as observers:
            if self.window or self.editing:
                swarm = self._show(config, world, make_swarm, [watch, *observers])
            else:
                swarm = make_swarm(world)
                self._can_save(swarm)
                say(opening_line(swarm, config))
                runner = Runner(swarm, [watch, *observers, RunProgress()], config.max_steps)
                with stopped_by_ctrl_c(runner):
                    runner.finish()
                interrupted = runner.stopped
            if swarm is None:
                return None
            if self.outputs.save_state:
                save(swarm, self.outputs.save_state, config)
            metrics = run_metrics(swarm)
            if self.outputs.metrics:
                text = json.dumps(metrics, indent=2, allow_nan=False) + "\n"
                write_text(self.outputs.metrics, text)
        say(summary_line(metrics))
        if interrupted:  # its outputs hold what it reached; the exit status says it was cut short
            raise KeyboardInterrupt
        return metrics

    def _can_save(self, swarm: Swarm) -> None:
        """With --save-state: refuse now, not after the run, a strategy that keeps what a state
        file cannot hold (it has set its attributes in `on_start` by now)."""
        if self.outputs.save_state is None:
            return
        try:
            swarm.snapshot()
        except SnapshotError as error:
            raise InputError(
                f"{self.outputs.save_state}: --save-state cannot save this run: {error}"
            ) from None

    def _loading(self) -> contextlib.AbstractContextManager[None]:
        """A failure of a strategy's own code (``file.py:Class``) as it is loaded and made is
        its own, said in one line (see `core.guard`)."""
        code = self.strategy if self.resume is not None else self.config.strategy
        if code is None or not strategies.is_code(code):
            return contextlib.nullcontext()
        return PluginCode.named(code).running(" as it was loaded")

    def _inputs(self) -> dict[Path, str]:
        """Every file the run reads, and what it is to the run (for messages)."""
        if self.resume is not None:
            return {self.resume: "the state this run resumes"} | strategy_file(self.strategy)
        return files_read(self.config)

    def _prepare(self) -> tuple[RunConfig, World, Callable[[World], Swarm]]:
        """The run's description, its first world, and how the run (and the window's restart)
        makes a swarm on a world."""
        config = self.config
        if self.resume is not None:
            saved, swarm = resume(self.resume, self.strategy)
            config = dataclasses.replace(saved, max_steps=config.max_steps)
            return config, swarm.world, lambda _: resume(self.resume, self.strategy)[1]
        path = config.shape
        if self.editing and (path is None or not path.exists()):  # a new drawing
            name = path.name if path else "untitled"
            world = blank_world(
                config.arena or BLANK_ARENA, BLANK_POSE, name, parse_colour(PALETTE[0])
            )
            return config, world, lambda painted: start_swarm(config, painted)
        world = load_world(config)
        start = start_cells(config, world)
        return config, world, lambda new: start_swarm(config, new, start if new is world else None)

    def _show(
        self,
        config: RunConfig,
        world: World,
        make_swarm: Callable[[World], Swarm],
        observers: list[Observer],
    ) -> Swarm | None:
        from swarmshape.ui.viewer import Viewer  # pygame only when a window is wanted

        if not self.editing:  # the editor runs nothing until a shape is handed over
            say(f"seed {config.seed}")
        viewer = Viewer(
            make_swarm,
            world,
            title=world.name,
            start=not self.editing,
            shape_file=config.shape,
            speed=self.speed,
            observers=observers,
            max_steps=config.max_steps,
        )
        viewer.run()  # closes the observers, as `Runner.finish` does
        return viewer.swarm


class SignalWatch(Observer):
    """Ends the run at the next step with a signal whose `Terminated` was swallowed: raised
    inside a callback from C code (numba compiling a kernel, through ctypes), it was printed
    as "Exception ignored" with a traceback, and the run went on to its end (the fuzz)."""

    def __init__(self) -> None:
        self.received: list[int] = []

    def capture(self, swarm: Swarm) -> None:
        self.raise_received()

    def raise_received(self) -> None:
        if self.received:
            raise Terminated(128 + self.received[0])


@contextlib.contextmanager
def ended_by_signals() -> Iterator[SignalWatch]:
    """SIGTERM and SIGHUP raise `Terminated` for a while, instead of ending the process where
    it stands (only the main thread receives signals; elsewhere nothing changes). A library
    that the signal strikes inside may turn it into an error of its own (pygame, loading a
    font, raised "TypeError: not a file object": an internal error, found by the fuzz): after
    a signal, whatever error comes out is the signal's. One that swallows it is caught by the
    `SignalWatch` this yields, as a run's observer, and as the block ends."""
    watch = SignalWatch()
    if threading.current_thread() is not threading.main_thread():
        yield watch
        return

    def end(number: int, _frame: object) -> None:
        watch.received.append(number)
        raise Terminated(128 + number)

    def unraisable(hook: Any) -> None:  # raised again by the watch: not printed here
        if not isinstance(hook.exc_value, Terminated):
            printed(hook)

    previous = {number: signal.signal(number, end) for number in (signal.SIGTERM, signal.SIGHUP)}
    printed, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield watch
        watch.raise_received()
    except Exception as error:
        if watch.received:
            raise Terminated(128 + watch.received[0]) from error
        raise
    finally:
        sys.unraisablehook = printed
        for number, handler in previous.items():
            signal.signal(number, handler)


@contextlib.contextmanager
def stopped_by_ctrl_c(runner: Runner) -> Iterator[None]:
    """A first Ctrl+C ends `runner`'s run after the step under way, so that its outputs and
    summary keep what it reached; a second one interrupts at once (the outputs not written by
    then are not written; each is written whole or not at all)."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or not callable(previous):
        yield  # signals reach only the main thread; an ignored Ctrl+C stays ignored
        return

    def stop(_number: int, _frame: object) -> None:
        runner.stop()
        signal.signal(signal.SIGINT, previous)

    signal.signal(signal.SIGINT, stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def say(line: str) -> None:
    """Print a line of the run's report; if the reader went away (``| head -1``), carry on
    quietly: the run and its files matter more than the report."""
    try:
        print(line, flush=True)
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


SHADES = ".:-=+*%#"
"""A picture's ink per cell in a preview, from none to all: the first four under half a cell
(which is no cell of the shape), the others half or more."""


def preview(config: RunConfig) -> str:
    """The shapes `config` forms, as text; an image's shape beside its picture at its size."""
    path = config.shape_path
    if path.suffix.lower() == ".toml":
        return preview_text(load_world(config))
    picture = read_picture(path, threshold=config.threshold, invert=config.invert)
    return preview_text(load_world(config, picture), picture)


def preview_text(world: World, picture: Picture | None = None) -> str:
    """Each group's shape as rows of # (a cell) and . (none), with its size; with a `picture`
    (a world of one image), the picture to its left at the same size, in `SHADES`."""
    parts = []
    for group in world.groups:
        grid = group.shape.grid
        head = (
            f"{group.name}: {int(grid.sum()):,} cells, {grid.shape[1]}x{grid.shape[0]}, "
            f"{group.agents:,} robots, scale {group.shape.scale:.2f}"
        )
        rows = ["".join("#" if cell else "." for cell in row) for row in grid.tolist()]
        if picture is not None:
            head += (
                f"; left, its picture by ink per cell ({SHADES[1:4]} under half, {SHADES[4:]} more)"
            )
            rows = _beside(_shaded(picture.ink, grid.shape), rows)
        parts.append("\n".join([head, *rows]))
    return "\n\n".join(parts)


def _shaded(ink: np.ndarray, shape: tuple[int, int]) -> list[str]:
    """Rows of `SHADES` for `ink` resized to `shape`."""
    share = resized(ink, shape)
    steps = len(SHADES) - 2  # SHADES[1] to SHADES[-2] for the shares between none and all
    index = np.where(share > 0, 1 + np.minimum(share * steps, steps).astype(int), 0)
    return ["".join(SHADES[i] for i in row) for row in index.tolist()]


def _beside(left: list[str], right: list[str]) -> list[str]:
    """Two blocks of text side by side, the shorter padded with blank rows."""
    width = max(len(row) for row in left)
    height = max(len(left), len(right))
    left += [""] * (height - len(left))
    right += [""] * (height - len(right))
    return [f"{a:<{width}}  {b}".rstrip() for a, b in zip(left, right, strict=True)]


def opening_line(swarm: Swarm, config: RunConfig) -> str:
    """What is about to run, said before it starts (a long run is not a silent one)."""
    world = swarm.world
    scale = min(g.shape.scale for g in world.groups)
    return (
        f"{world.name}: {_count(world.agents, 'robot')} for {_count(len(world.targets), 'cell')}"
        f" (scale {scale:.2f}), {swarm.plugin.name}, seed {config.seed}, "
        f"at most {config.max_steps:,} steps"
    )


def summary_line(metrics: dict[str, Any]) -> str:
    """One human line for the terminal."""
    formed = (
        f"formed in {_count(metrics['steps'], 'step')}"
        if metrics["steps"] is not None
        else f"not formed after {_count(metrics['steps_run'], 'step')}"
    )
    ratio = metrics["makespan_ratio"]
    versus = "" if ratio is None else f", {ratio:.2f}x the makespan lower bound ({_how(metrics)})"
    return (
        f"{metrics['shape']}: {metrics['strategy']}, {_count(metrics['agents'], 'robot')}, "
        f"{_count(metrics['targets'], 'target')}, scale {metrics['scale']:.2f}: {formed}, "
        f"coverage {100 * metrics['coverage']:.1f}%, iou {metrics['iou']:.3f}, "
        f"{_count(metrics['overlaps'], 'overlap')}, seed {metrics['seed']}{versus}"
        f"{_fault_summary(metrics)}"
    )


def _fault_summary(metrics: dict[str, Any]) -> str:
    """What faults did, if there were any: robots lost and stalled, and the recoveries."""
    faults = metrics["faults"]
    if not faults:
        return ""
    recovered = [f["recovery_steps"] for f in faults if f["recovery_steps"] is not None]
    slowest = f", the slowest in {_count(max(recovered), 'step')}" if recovered else ""
    stalls = metrics["cells_lost_to_stalls"]
    notes = [f"{_count(stalls, 'cell')} lost to stalled robots"] if stalls else []
    if metrics["steps"] is not None and metrics["cells_left_open"]:  # formed, short of robots
        notes.append(f"{_count(metrics['cells_left_open'], 'cell')} left open: too few robots")
    lost = f" ({'; '.join(notes)})" if notes else ""
    return (
        f"; {_count(len(faults), 'fault')}: {_count(metrics['robots_lost'], 'robot')} lost, "
        f"{metrics['robots_stalled']:,} stalled{lost}, {len(recovered)} recovered{slowest}"
    )


def _how(metrics: dict[str, Any]) -> str:
    """Whether the makespan bound is the optimum or only a bound, and which."""
    if metrics["makespan_bound_exact"]:
        return "exact"
    return f"{metrics['makespan_bound_method']} bound, not proved exact"


def _count(number: int, thing: str) -> str:
    return f"{number:,} {thing}{'' if number == 1 else 's'}"


def _same(path: Path, other: Path) -> bool:
    return path.resolve() == other.resolve() or identity(path) == identity(other) is not None

"""A run with its outputs, in a window or headless: what ``swarmshape run`` and ``edit`` do.

The outputs are checked before anything runs, observers record while it runs, and the state,
the metrics and the summary are written at the end. The command line only maps its options
onto `Outputs` and `Session` and its exit codes.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmshape.core.metrics import run_metrics
from swarmshape.core.shape import Pose
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import World, blank_world
from swarmshape.experiments.progress import RunProgress
from swarmshape.experiments.trace import Trace
from swarmshape.io.files import check_output, write_text
from swarmshape.io.scenario import PALETTE, parse_colour, read_start_cells
from swarmshape.runs import Observer, RunConfig, Runner, load_world, resume, save, start_swarm

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
    trace: Path | None = None
    trace_every: int = 1
    save_state: Path | None = None
    force: bool = False

    def check(self, resumed: Path | None = None) -> None:
        """Fail before the run, not after it, when an output cannot be written or would
        replace a file the user did not ask to replace (`force`, or the state being resumed)."""
        for option in ("metrics", "record", "trace", "save_state", "frames"):
            path = getattr(self, option)
            if path is not None:
                may_replace = self.force or (resumed is not None and _same(path, resumed))
                check_output(path, "--" + option.replace("_", "-"), may_replace=may_replace)

    def observers(self) -> list[Observer]:
        """Recording and tracing, as asked for."""
        observers: list[Observer] = []
        if self.record or self.frames:
            from swarmshape.ui.record import Recorder  # draws with pygame, offscreen

            observers.append(Recorder(self.record, self.frames, self.record_every))
        if self.trace:
            observers.append(Trace(self.trace, self.trace_every))
        return observers


@dataclass(frozen=True)
class Session:
    """One ``run`` or ``edit``: what to run (a description, or a saved state to resume), how
    (a window, the editor, or headless) and where its outputs go. A resumed run takes only
    ``max_steps`` from `config`; the rest was saved with it."""

    config: RunConfig
    outputs: Outputs
    resume: Path | None = None
    window: bool = True
    editing: bool = False
    speed: float = 8

    def start(self) -> dict[str, Any] | None:
        """Run it; return the headless run's metrics (None after a window)."""
        self.outputs.check(self.resume)
        config, world, make_swarm = self._prepare()
        observers = self.outputs.observers()
        if self.window or self.editing:
            swarm = self._show(config, world, make_swarm, observers)
        else:
            runner = Runner(make_swarm(world), [*observers, RunProgress()], config.max_steps)
            swarm = runner.finish()
        if swarm is None:  # the editor closed before any swarm ran
            return None
        if self.outputs.save_state:
            save(swarm, self.outputs.save_state, config)
        if self.window or self.editing:
            return None
        metrics = run_metrics(swarm)
        print(summary_line(metrics))
        if self.outputs.metrics:
            write_text(self.outputs.metrics, json.dumps(metrics, indent=2) + "\n")
        return metrics

    def _prepare(self) -> tuple[RunConfig, World, Callable[[World], Swarm]]:
        """The run's description, its first world, and how the run (and the window's restart)
        makes a swarm on a world."""
        config = self.config
        if self.resume is not None:
            saved, swarm = resume(self.resume)
            config = dataclasses.replace(saved, max_steps=config.max_steps)
            return config, swarm.world, lambda _: resume(self.resume)[1]
        path = config.shape
        if self.editing and (path is None or not path.exists()):  # a new drawing
            name = path.name if path else "untitled"
            world = blank_world(
                config.arena or BLANK_ARENA, BLANK_POSE, name, parse_colour(PALETTE[0])
            )
            return config, world, lambda painted: start_swarm(config, painted)
        world = load_world(config)
        start = None if config.start is None else read_start_cells(config.start, world)
        return config, world, lambda new: start_swarm(config, new, start if new is world else None)

    def _show(
        self,
        config: RunConfig,
        world: World,
        make_swarm: Callable[[World], Swarm],
        observers: list[Observer],
    ) -> Swarm | None:
        from swarmshape.ui.viewer import Viewer  # pygame only when a window is wanted

        print(f"seed {config.seed}")
        viewer = Viewer(
            make_swarm,
            world,
            title=world.name,
            start=not self.editing,
            shape_file=self.config.shape if self.editing else None,
            speed=self.speed,
            observers=observers,
        )
        viewer.run()
        if viewer.swarm is not None:
            for observer in observers:
                observer.close(viewer.swarm)
        return viewer.swarm


def summary_line(metrics: dict[str, Any]) -> str:
    """One human line for the terminal."""
    formed = (
        f"formed in {metrics['steps']} steps"
        if metrics["steps"] is not None
        else f"not formed after {metrics['steps_run']} steps"
    )
    ratio = metrics["makespan_ratio"]
    versus = "" if ratio is None else f", {ratio:.2f}x the makespan lower bound"
    return (
        f"{metrics['shape']}: {metrics['strategy']}, {metrics['agents']} agents, "
        f"{metrics['targets']} targets, scale {metrics['scale']:.2f}: {formed}, "
        f"coverage {100 * metrics['coverage']:.1f}%, iou {metrics['iou']:.3f}, "
        f"{metrics['overlaps']} overlaps, seed {metrics['seed']}{versus}"
    )


def _same(path: Path, other: Path) -> bool:
    return path.resolve() == other.resolve()

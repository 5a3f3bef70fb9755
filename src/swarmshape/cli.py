"""Command line: ``swarmshape [run] [PATH] [options]`` and ``swarmshape strategies``.

Bad input of any kind ends in one line on stderr and exit code 2; the viewer and pygame are
only imported when a window is wanted.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import traceback
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import metadata, resources
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from swarmshape import strategies
from swarmshape.bitmap import DEFAULT_CELLS, DEFAULT_THRESHOLD
from swarmshape.errors import InputError
from swarmshape.files import write_text
from swarmshape.fill_order import ORDERS
from swarmshape.metrics import run_metrics, summary_line
from swarmshape.motion import Limits
from swarmshape.progress import ProgressBar
from swarmshape.scenario import (
    PALETTE,
    ImageOptions,
    Scenario,
    load_scenario,
    parse_colour,
    read_start_cells,
)
from swarmshape.shape import Pose
from swarmshape.state import load_state, save_state
from swarmshape.swarm import Params, Swarm
from swarmshape.trace import Trace
from swarmshape.world import World, blank_world, build_world

DEFAULT_SHAPE = "horseshoe.png"
DEFAULT_STRATEGY = "optimal"
DEFAULT_MAX_STEPS = 500_000
COMMANDS = ("run", "edit", "sweep", "plot", "strategies")
BLANK_ARENA = (48, 30)
BLANK_POSE = Pose(4, 4)


def bundled_shapes() -> Path:
    """The shipped shapes: inside an installed wheel, or the source checkout's shapes/."""
    installed = resources.files("swarmshape") / "shapes"
    if installed.is_dir():
        return Path(str(installed))
    return Path(__file__).resolve().parents[2] / "shapes"


class Parser(argparse.ArgumentParser):
    """argparse, but a mistake is one line on stderr like every other bad input."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"swarmshape: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="swarmshape",
        description="Watch a swarm of square robots organise itself into a shape.",
        epilog="Commands: run (the default), edit and strategies. See 'swarmshape run --help'.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(dest="command")
    shared = _shared_options()
    run = commands.add_parser(
        "run",
        parents=[shared],
        help="form a shape (the default command)",
        description="Form the shape of an image or a .toml scenario, in a window or headless.",
    )
    run.add_argument(
        "path",
        nargs="?",
        type=Path,
        help=f"an image (PNG, GIF, BMP, JPEG, WebP) or a .toml scenario "
        f"(default: the bundled {DEFAULT_SHAPE})",
    )
    out = run.add_argument_group("output")
    out.add_argument("--headless", action="store_true", help="no window: run, print a summary")
    out.add_argument(
        "--max-steps", type=int, help=f"stop after this many steps (default {DEFAULT_MAX_STEPS})"
    )
    out.add_argument("--metrics", type=Path, help="write the run's metrics as JSON to this file")
    edit = commands.add_parser(
        "edit",
        parents=[shared],
        help="paint a shape, then watch the swarm form it",
        description="Paint a shape on the arena with the mouse (h shows the keys); Enter hands "
        "it to a swarm, which you can keep re-shaping with e.",
    )
    edit.add_argument(
        "path",
        nargs="?",
        type=Path,
        help="the image to edit; a new file starts blank and is where Ctrl+S saves",
    )
    sweep = commands.add_parser(
        "sweep",
        help="run many headless runs in parallel, one CSV row each",
        description="Run the cross product of a sweep file's shapes, strategies, agent counts "
        "and seeds; resumable (finished rows are skipped).",
    )
    sweep.add_argument("file", type=Path, help="a sweep .toml (see sweeps/strategies.toml)")
    sweep.add_argument("--out", type=Path, help="results CSV (default: beside the sweep file)")
    sweep.add_argument("--workers", type=int, help="local processes (default: one per core)")
    sweep.add_argument("--dask", metavar="ADDRESS", help="run on a Dask cluster, tcp://HOST:PORT")
    plot = commands.add_parser("plot", help="plot a sweep's results (needs the plot extra)")
    plot.add_argument("results", type=Path, help="a CSV written by swarmshape sweep")
    plot.add_argument("--out", type=Path, help="folder for the plots (default: beside it)")
    plot.add_argument(
        "--format", choices=("png", "svg"), action="append", help="png (default), svg"
    )
    plot.add_argument("--force", action="store_true", help="overwrite existing plots")
    commands.add_parser("strategies", help="list the available strategies")
    return parser


def _shared_options() -> argparse.ArgumentParser:
    """Options of both run and edit."""
    shared = Parser(add_help=False)
    shared.add_argument("--seed", type=int, help="random seed (default: a fresh one, printed)")
    shared.add_argument("--agents", type=int, help="number of agents (default: one per cell)")
    shared.add_argument(
        "--strategy",
        help=f"who goes where: a name from 'swarmshape strategies' or package.module:Class "
        f"(default {DEFAULT_STRATEGY})",
    )
    shared.add_argument(
        "--order", choices=ORDERS, help="the paper strategy's fill order (default outward)"
    )
    image = shared.add_argument_group("image loading")
    image.add_argument(
        "--cells",
        type=int,
        default=DEFAULT_CELLS,
        help=f"longest side of the shape in cells; larger images shrink (default {DEFAULT_CELLS})",
    )
    image.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_THRESHOLD,
        help=f"luminance 0..1 between ink and background (default {DEFAULT_THRESHOLD})",
    )
    image.add_argument("--invert", action="store_true", help="the ink is the light part")
    sim = shared.add_argument_group("simulation")
    sim.add_argument("--arena", type=_size, help="arena size in cells as WxH (default: automatic)")
    sim.add_argument("--max-speed", type=float, help="cells per step (default 0.5)")
    sim.add_argument("--max-accel", type=float, help="cells per step squared (default 0.125)")
    sim.add_argument("--speed", type=float, default=8, help="window: steps per frame (default 8)")
    sim.add_argument(
        "--start", type=Path, help="CSV of start cells (columns x,y, one row per agent)"
    )
    sim.add_argument(
        "--load-state", type=Path, help="resume a run saved with --save-state (PATH not needed)"
    )
    record = shared.add_argument_group("recording")
    record.add_argument("--record", type=Path, help="write an animation: .gif, .webp or .png")
    record.add_argument("--frames", type=Path, help="write numbered PNG frames to this folder")
    record.add_argument(
        "--record-every", type=int, default=1, help="record every K-th step (default 1)"
    )
    record.add_argument("--trace", type=Path, help="write figures per step as CSV")
    record.add_argument(
        "--trace-every", type=int, default=1, help="trace every K-th step (default 1)"
    )
    record.add_argument(
        "--save-state", type=Path, help="save the whole run at its end, to resume it later"
    )
    record.add_argument("--force", action="store_true", help="overwrite existing output files")
    return shared


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT, e.g. 60x40, got {text!r}"
        ) from None
    return width, height


def _version() -> str:
    try:
        return metadata.version("swarmshape")
    except metadata.PackageNotFoundError:
        return "unknown"


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help", "--version")):
        argv.insert(0, "run")
    args = build_parser().parse_args(argv)
    try:
        if args.command == "strategies":
            return list_strategies()
        if args.command == "sweep":
            return run_sweep(args)
        if args.command == "plot":
            return run_plot(args)
        return run(args)
    except InputError as error:
        print(f"swarmshape: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except Exception:  # a bug of ours: a short word here, the whole story in a log
        log = Path(tempfile.gettempdir()) / f"swarmshape-crash-{os.getpid()}.log"
        log.write_text(traceback.format_exc(), encoding="utf-8")
        print(f"swarmshape: internal error, please report it; details in {log}", file=sys.stderr)
        return 1


def run_sweep(args: argparse.Namespace) -> int:
    from swarmshape.sweep import read_sweep, sweep

    runs = read_sweep(args.file)
    out = args.out or args.file.with_suffix(".csv")
    bar = ProgressBar()
    ran = sweep(
        runs,
        out,
        args.file.parent,
        dask=args.dask,
        workers=args.workers,
        progress=lambda done, total: bar.show(done / total, f"{done}/{total} runs", now=True),
    )
    bar.done()
    print(f"{out}: {ran} runs done now, {len(runs) - ran} were there already")
    return 0


def run_plot(args: argparse.Namespace) -> int:
    from swarmshape.plot import plot_results

    out = args.out or args.results.parent
    formats = tuple(args.format or ["png"])
    for path in plot_results(args.results, out, formats, force=args.force):
        print(path)
    return 0


def list_strategies() -> int:
    known = strategies.available()
    width = max(len(name) for name in known)
    for name, cls in sorted(known.items()):
        print(f"{name:<{width}}  {cls.description}")
    return 0


@dataclass(frozen=True)
class Prepared:
    """A run ready to start: its name, final settings, its world, and how to start a swarm."""

    name: str
    settings: dict[str, Any]
    world: World
    make_swarm: Callable[[World], Swarm]


def prepare(args: argparse.Namespace) -> Prepared:
    """Load the scenario (or a saved run, or a blank canvas), merge the options, build the world."""
    if args.load_state is not None:
        saved = load_state(args.load_state)
        settings = {"strategy": saved.strategy, "seed": saved.swarm.seed, **_run_limits(args)}
        return Prepared(
            saved.name, settings, saved.swarm.world, lambda _: load_state(args.load_state).swarm
        )
    editing = args.command == "edit"
    if editing and (args.path is None or not args.path.exists()):  # a new drawing
        scenario = Scenario(args.path.name if args.path else "untitled", ())
    else:
        path = args.path or bundled_shapes() / DEFAULT_SHAPE
        scenario = load_scenario(path, ImageOptions(args.cells, args.threshold, args.invert))
    settings = _settings(scenario, args)
    specs = list(scenario.groups)
    if args.agents is not None:
        if len(specs) > 1:
            raise InputError("--agents applies to one shape; set agents per group in the scenario")
        if specs:
            specs[0] = replace(specs[0], agents=args.agents)
    if specs:
        world = build_world(specs, args.arena or scenario.arena)
    else:
        colour = parse_colour(PALETTE[0])
        world = blank_world(args.arena or BLANK_ARENA, BLANK_POSE, scenario.name, colour)
    strategies.get(settings["strategy"])  # fail now, not inside the window
    params = Params(limits=Limits(settings["max_speed"], settings["max_accel"]))
    start = None if args.start is None or not specs else read_start_cells(args.start, world)

    def make_swarm(new_world: World) -> Swarm:
        strategy = strategies.create(settings["strategy"], order=settings["order"])
        cells = start if new_world is world else None  # start cells fit the first world only
        return Swarm(new_world, strategy, settings["seed"], params, cells)

    return Prepared(scenario.name, settings, world, make_swarm)


def run(args: argparse.Namespace) -> int:
    for option in ("metrics", "record", "trace", "save_state", "frames"):
        _check_output(getattr(args, option, None), option, args)
    prepared = prepare(args)
    settings = prepared.settings
    observers = _observers(args)
    editing = args.command == "edit"
    if editing or not args.headless:
        from swarmshape.viewer import Viewer  # pygame only when a window is wanted

        print(f"seed {settings['seed']}")
        viewer = Viewer(
            prepared.make_swarm,
            prepared.world,
            title=prepared.name,
            start=not editing,
            shape_file=args.path if editing else None,
            speed=args.speed,
            observers=observers,
        )
        viewer.run()
        swarm = viewer.swarm
    else:
        swarm = prepared.make_swarm(prepared.world)
        _run_headless(swarm, settings["max_steps"], observers)
    if swarm is None:  # the editor closed before any swarm ran
        return 0
    for observer in observers:
        observer.close(swarm)
    if args.save_state:
        save_state(swarm, args.save_state, name=prepared.name, strategy=settings["strategy"])
    if editing or not args.headless:
        return 0
    metrics = run_metrics(swarm, prepared.name, settings["strategy"])
    print(summary_line(metrics))
    if args.metrics:
        write_text(args.metrics, json.dumps(metrics, indent=2) + "\n")
    return 0


def _observers(args: argparse.Namespace) -> list:
    """Recording and tracing, as asked for; each captures the swarm after every step."""
    observers = []
    if args.record or args.frames:
        from swarmshape.record import Recorder  # draws with pygame, offscreen

        observers.append(Recorder(args.record, args.frames, args.record_every))
    if args.trace:
        observers.append(Trace(args.trace, args.trace_every))
    return observers


def _run_headless(swarm: Swarm, max_steps: int, observers: list) -> None:
    """Step to completion or `max_steps`, feeding the observers, with a progress bar."""
    bar = ProgressBar()
    for observer in observers:
        observer.capture(swarm)
    while not swarm.complete and swarm.step_count < max_steps:
        swarm.step()
        for observer in observers:
            observer.capture(swarm)
        coverage = swarm.filled.mean()
        bar.show(coverage, f"coverage {100 * coverage:5.1f}%  step {swarm.step_count}")
    bar.done()


def _check_output(path: Path | None, option: str, args: argparse.Namespace) -> None:
    """Fail before the run, not after it, when an output cannot be written, or would
    overwrite a file the user did not ask to replace (--force, or the state being resumed)."""
    if path is None:
        return
    flag = "--" + option.replace("_", "-")
    replaces = path.is_file() or (option == "frames" and path.is_dir() and any(path.iterdir()))
    resumed = args.load_state is not None and path.resolve() == args.load_state.resolve()
    if replaces and not args.force and not resumed:
        raise InputError(f"{path}: {flag} would overwrite it; add --force to allow that")
    if option != "frames" and path.is_dir():
        raise InputError(f"{path}: {flag} needs a file name, and this is a folder")
    # a file goes into an existing folder; the frames folder may be made, inside one
    existing = path if option == "frames" and path.is_dir() else path.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise InputError(f"{path}: {flag} cannot write there (no such folder, or no permission)")


def _run_limits(args: argparse.Namespace) -> dict[str, Any]:
    steps = getattr(args, "max_steps", None)
    return {"max_steps": DEFAULT_MAX_STEPS if steps is None else steps}


def _settings(scenario: Scenario, args: argparse.Namespace) -> dict[str, Any]:
    """Command-line options win over the scenario's values, which win over defaults."""
    defaults = {
        "strategy": DEFAULT_STRATEGY,
        "order": "outward",
        "seed": None,
        "max_steps": DEFAULT_MAX_STEPS,
        "max_speed": Limits.max_speed,
        "max_accel": Limits.max_accel,
    }
    chosen = {**defaults, **scenario.settings}
    for key in defaults:
        value = getattr(args, key, None)
        if value is not None:
            chosen[key] = value
    if chosen["seed"] is None:
        chosen["seed"] = int(np.random.SeedSequence().generate_state(1)[0])
    if not 0 <= chosen["seed"] < 2**63:
        raise InputError(f"--seed must be a whole number from 0 to 2**63 - 1, got {chosen['seed']}")
    if chosen["order"] not in ORDERS:
        raise InputError(f"unknown order {chosen['order']!r}; choose one of {', '.join(ORDERS)}")
    if chosen["max_steps"] < 0:
        raise InputError(f"--max-steps must be 0 or more, got {chosen['max_steps']}")
    return chosen

"""Command line: ``swarmshape [run] [PATH] [options]`` and the other commands; grammar and
dispatch only.

Bad input of any kind ends in one line on stderr and exit code 2; a bug of ours in one line
pointing to a log, exit code 1. The window (and pygame) is only loaded when one is wanted.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import os
import sys
import tempfile
import traceback
import warnings
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import NoReturn

from swarmshape.core.faults import FaultEvent, parse_event, parse_region
from swarmshape.core.world import START_LAYOUTS
from swarmshape.errors import InputError
from swarmshape.runs import DEFAULT_SHAPE, RunConfig, configure, load_world, resume, start_of
from swarmshape.session import Outputs, Session, preview_text
from swarmshape.strategies.fill_order import ORDERS

COMMANDS = ("run", "edit", "sweep", "plot", "strategies", "check")
NOT_FORMED = 3
"""Exit status of a headless run that stopped before its shape formed (and of a failed check)."""
RUN_OPTIONS = ("strategy", "order", "seed", "agents", "cells", "threshold", "arena",
               "max_speed", "max_accel", "max_steps", "start", "fit", "speed_variation",
               "sense_radius", "distance_noise", "msg_loss", "failure_rate")  # fmt: skip
"""Command-line options that are fields of `RunConfig` (``--invert`` too, when given)."""


class Parser(argparse.ArgumentParser):
    """argparse, but a mistake is one line on stderr like every other bad input."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"swarmshape: error: {_one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="swarmshape",
        description="Watch a swarm of square robots organise itself into a shape.",
        epilog="Commands: run (the default), edit, sweep, plot, strategies and check. "
        "See 'swarmshape COMMAND --help'.",
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
        "--max-steps",
        type=int,
        help=f"stop after this many steps (default {RunConfig.max_steps})",
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
    sweep.add_argument(
        "--force",
        action="store_true",
        help="let --out replace a file that is not this sweep's results, or start one over",
    )
    plot = commands.add_parser("plot", help="plot a sweep's results (needs the plot extra)")
    plot.add_argument("results", type=Path, help="a CSV written by swarmshape sweep")
    plot.add_argument("--out", type=Path, help="folder for the plots (default: beside it)")
    plot.add_argument(
        "--format", choices=("png", "svg"), action="append", help="png (default), svg"
    )
    plot.add_argument("--force", action="store_true", help="overwrite existing plots")
    commands.add_parser("strategies", help="list the available strategies")
    check = commands.add_parser(
        "check",
        help="run a strategy on small random shapes and report any broken invariant",
        description="Run a strategy on small random shapes, twice per seed, and report in plain "
        "words any overlap, robot leaving the arena, settled robot moving, run that differs for "
        "the same seed, or shape never formed. Exit 0 when clean, 3 when something broke.",
    )
    check.add_argument("strategy", help="a name from 'swarmshape strategies' or module:Class")
    check.add_argument("--runs", type=int, default=20, help="random shapes to try (default 20)")
    check.add_argument("--seed", type=int, default=0, help="seed of the first shape (default 0)")
    check.add_argument(
        "--max-steps", type=int, default=20_000, help="steps to form each shape (default 20000)"
    )
    return parser


def _shared_options() -> argparse.ArgumentParser:
    """Options of both run and edit; unset ones fall back to the scenario, then the defaults."""
    defaults = RunConfig()
    shared = Parser(add_help=False)
    shared.add_argument("--seed", type=int, help="random seed (default: a fresh one, printed)")
    shared.add_argument("--agents", type=int, help="number of robots (default: one per cell)")
    shared.add_argument(
        "--strategy",
        help=f"who goes where: a name from 'swarmshape strategies' or package.module:Class "
        f"(default {defaults.strategy})",
    )
    shared.add_argument(
        "--order",
        choices=ORDERS,
        help=f"the paper strategy's fill order (default {defaults.order})",
    )
    image = shared.add_argument_group("image loading")
    image.add_argument(
        "--cells",
        type=int,
        help="cells across the shape's long side; images shrink or grow to it "
        "(default: the image's own size, at most 32)",
    )
    image.add_argument(
        "--threshold",
        type=float,
        help=f"luminance 0..1 between ink and background (default {defaults.threshold})",
    )
    image.add_argument("--invert", action="store_true", help="the ink is the light part")
    image.add_argument(
        "--fit",
        choices=("agents",),
        help="agents: size the shape to --agents (as many cells as robots, or just fewer)",
    )
    image.add_argument(
        "--preview", action="store_true", help="print the shape as text and stop (no run)"
    )
    sim = shared.add_argument_group("simulation")
    sim.add_argument("--arena", type=_size, help="arena size in cells as WxH (default: automatic)")
    sim.add_argument(
        "--max-speed", type=float, help=f"cells per step (default {defaults.max_speed})"
    )
    sim.add_argument(
        "--max-accel", type=float, help=f"cells per step squared (default {defaults.max_accel})"
    )
    sim.add_argument(
        "--speed-variation",
        type=float,
        help="each robot's top speed is --max-speed times a factor from [1 - V, 1] (default 0)",
    )
    sim.add_argument("--speed", type=float, default=8, help="window: steps per frame (default 8)")
    local = shared.add_argument_group("local programs (what a robot senses)")
    local.add_argument(
        "--sense-radius",
        type=float,
        help="cells within which a robot senses and hears others "
        f"(default {defaults.sense_radius:g})",
    )
    local.add_argument(
        "--distance-noise",
        type=float,
        help="standard deviation of sensed offsets, in cells (default 0)",
    )
    local.add_argument(
        "--msg-loss",
        type=float,
        help="chance per step that a link between neighbours fails; Kilombo's msgSuccessRate is "
        "1 - P (default 0)",
    )
    sim.add_argument(
        "--start",
        type=_start,
        help="where robots start: packed (a block against the seeds, as in the Kilobot "
        "self-assembly experiments), scatter (random free cells, the default), or a CSV of "
        "start cells (columns x,y, one row per robot)",
    )
    sim.add_argument(
        "--load-state", type=Path, help="resume a run saved with --save-state (PATH not needed)"
    )
    faults = shared.add_argument_group("faults")
    faults.add_argument(
        "--fail",
        action="append",
        metavar="FRACTION@STEP",
        help="remove that fraction of the robots (or a number, e.g. 50@300), chosen at random, "
        "at that step; repeatable",
    )
    faults.add_argument(
        "--fail-region",
        action="append",
        metavar="X,Y,W,H@STEP",
        help="remove every robot in that rectangle of cells (X,Y,R: a disc) at that step; "
        "repeatable",
    )
    faults.add_argument(
        "--stall",
        action="append",
        metavar="FRACTION@STEP",
        help="stop that fraction of the robots for good where they stand; repeatable",
    )
    faults.add_argument(
        "--failure-rate",
        type=float,
        metavar="P",
        help="each robot fails (is removed) with probability P per step (default 0)",
    )
    record = shared.add_argument_group("recording")
    record.add_argument("--record", type=Path, help="write an animation: .gif, .webp, .png or .mp4")
    record.add_argument("--frames", type=Path, help="write numbered PNG frames to this folder")
    record.add_argument(
        "--record-every", type=int, default=1, help="record every K-th step (default 1)"
    )
    record.add_argument(
        "--record-size",
        type=_size,
        help="recorded frame size in pixels, WxH (default 640x400)",
    )
    record.add_argument("--trace", type=Path, help="write figures per step as CSV")
    record.add_argument(
        "--trace-every", type=int, default=1, help="trace every K-th step (default 1)"
    )
    record.add_argument(
        "--save-state", type=Path, help="save the whole run at its end, to resume it later"
    )
    record.add_argument(
        "--positions", type=Path, help="write every robot's position per step: .npz or .csv"
    )
    record.add_argument(
        "--positions-every", type=int, default=1, help="positions every K-th step (default 1)"
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


def _start(text: str) -> str | Path:
    """A start layout by name, or a CSV of start cells (see `runs.start_of`)."""
    try:
        return start_of(text)
    except InputError:
        raise argparse.ArgumentTypeError(
            f"expected {', '.join(START_LAYOUTS)} or a CSV file of start cells, got {text!r}"
        ) from None


def _version() -> str:
    try:
        return metadata.version("swarmshape")
    except metadata.PackageNotFoundError:
        return "unknown"


MMAP_THRESHOLD = 32 << 20
TRIM_THRESHOLD = 64 << 20
"""glibc's ``mallopt`` settings for a run (see `_reuse_freed_memory`)."""


def _reuse_freed_memory() -> None:
    """Let glibc keep freed arrays for reuse. By default every array over 128 KiB is a fresh
    ``mmap`` whose pages fault in again, and a step allocates dozens of them: 1,500 steps of
    the 1,024-robot self-assembly K took 26.8 s (2.2 s of it in the kernel), 17.8 s with
    these settings. Elsewhere (no glibc) nothing changes."""
    library = ctypes.util.find_library("c")
    mallopt = getattr(ctypes.CDLL(library), "mallopt", None) if library else None
    if mallopt is not None:
        mallopt(-3, MMAP_THRESHOLD)  # M_MMAP_THRESHOLD
        mallopt(-1, TRIM_THRESHOLD)  # M_TRIM_THRESHOLD


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help", "--version")):
        argv.insert(0, "run")
    args = build_parser().parse_args(argv)
    warnings.showwarning = _first_warning()
    _reuse_freed_memory()
    try:
        return COMMAND_FUNCTIONS[args.command](args)
    except InputError as error:
        print(f"swarmshape: error: {_one_line(str(error))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("swarmshape: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of a listing went away (| head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except Exception:  # a bug of ours: a short word here, the whole story in a log
        print(f"swarmshape: internal error, please report it; {_crash_log()}", file=sys.stderr)
        return 1


def _first_warning() -> Callable[..., None]:
    """How a command shows warnings: as one line on stderr, like an error, without a source
    line below it; and only its first, which names the option that helps (a picture squeezed
    into one cell also has too many robots for it: raising --cells cures both)."""
    shown = False

    def show(message: Warning | str, category: type, *_: object, **__: object) -> None:
        nonlocal shown
        if not shown:
            print(f"swarmshape: warning: {_one_line(str(message))}", file=sys.stderr)
            shown = True

    return show


def _one_line(text: str) -> str:
    """`text` with line breaks and other unprintable characters written as escapes (a file
    named "a\\nb" is shown so): a message is one line, whatever names it quotes."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)


def _crash_log() -> str:
    """Write the traceback to a fresh, private log file; say where (or, failing that, what)."""
    details = traceback.format_exc()
    try:
        fd, path = tempfile.mkstemp(prefix="swarmshape-crash-", suffix=".log")
        with os.fdopen(fd, "w", encoding="utf-8") as log:
            log.write(details)
    except OSError:
        return f"no log could be written ({details.strip().splitlines()[-1]})"
    return f"details in {path}"


def run_session(args: argparse.Namespace) -> int:
    """``run`` and ``edit``: a run described by the options, or a saved one resumed."""
    max_steps = getattr(args, "max_steps", None)
    given = {name: getattr(args, name, None) for name in RUN_OPTIONS}
    given["invert"] = args.invert or None
    given["faults"] = fault_events(args)
    if args.load_state is not None:
        _nothing_that_a_resume_ignores(args, given)
        config = RunConfig(**({} if max_steps is None else {"max_steps": max_steps}))
    else:
        config = configure(args.path, **given)
    if args.preview:
        if args.load_state is not None:  # the saved run's shape, not the default one
            world = resume(args.load_state, args.strategy)[1].world
        else:
            world = load_world(config)
        print(preview_text(world))
        return 0
    outputs = Outputs(
        metrics=getattr(args, "metrics", None),
        record=args.record,
        frames=args.frames,
        record_every=args.record_every,
        record_size=args.record_size,
        trace=args.trace,
        trace_every=args.trace_every,
        save_state=args.save_state,
        positions=args.positions,
        positions_every=args.positions_every,
        force=args.force,
    )
    editing = args.command == "edit"
    window = editing or not args.headless
    metrics = Session(
        config,
        outputs,
        resume=args.load_state,
        strategy=args.strategy,
        window=window,
        editing=editing,
        speed=args.speed,
    ).start()
    return NOT_FORMED if not window and metrics["steps"] is None else 0


def fault_events(args: argparse.Namespace) -> tuple[FaultEvent, ...] | None:
    """The fault options as events, in the order given; None when there are none."""
    events = [parse_event(text, "remove", "--fail") for text in args.fail or ()]
    events += [parse_region(text) for text in args.fail_region or ()]
    events += [parse_event(text, "stall", "--stall") for text in args.stall or ()]
    return tuple(events) or None


def _nothing_that_a_resume_ignores(args: argparse.Namespace, given: dict) -> None:
    """A saved run resumes exactly as it was: options that would change it are refused rather
    than silently ignored (--strategy may only name the code a run was saved with)."""
    if args.path is not None:
        raise InputError(f"--load-state resumes a saved run; {args.path} would not be used")
    ignored = [name for name, value in given.items() if value is not None]
    ignored = [name for name in ignored if name not in ("max_steps", "strategy")]
    if ignored:
        flag = "--" + ignored[0].replace("_", "-")
        raise InputError(f"--load-state resumes a saved run as it was; {flag} cannot change it")


def run_sweep(args: argparse.Namespace) -> int:
    from swarmshape.experiments.sweep import run_sweep_file

    return run_sweep_file(
        args.file, args.out, dask=args.dask, workers=args.workers, force=args.force
    )


def run_plot(args: argparse.Namespace) -> int:
    from swarmshape.experiments.plot import plot_results

    out = args.out or args.results.parent
    formats = tuple(args.format or ["png"])
    for path in plot_results(args.results, out, formats, force=args.force):
        print(path)
    return 0


def list_strategies(args: argparse.Namespace) -> int:
    from swarmshape.strategies import available

    known = available()
    width = max(len(name) for name in known)
    for name, cls in sorted(known.items()):
        print(f"{name:<{width}}  {cls.kind:<7}  {cls.description}")
    return 0


def run_check(args: argparse.Namespace) -> int:
    from swarmshape.check import check_strategy

    if args.runs < 1:
        raise InputError(f"--runs must be at least 1, got {args.runs}")
    if args.max_steps < 0:
        raise InputError(f"--max-steps must be 0 or more, got {args.max_steps}")
    if args.seed < 0:
        raise InputError(f"--seed must be a whole number of 0 or more, got {args.seed}")
    report = check_strategy(args.strategy, runs=args.runs, seed=args.seed, max_steps=args.max_steps)
    print(report.text())
    return 0 if report.clean else NOT_FORMED


COMMAND_FUNCTIONS = {
    "run": run_session,
    "edit": run_session,
    "sweep": run_sweep,
    "plot": run_plot,
    "strategies": list_strategies,
    "check": run_check,
}

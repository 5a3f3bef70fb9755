"""Command line: ``swarmshape [run] [PATH] [options]`` and the other commands; grammar and
dispatch only.

Bad input of any kind ends in one line on stderr and exit code 2; a bug of ours in one line
pointing to a log, exit code 1. The window (and pygame) is only loaded when one is wanted.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import math
import os
import sys
import tempfile
import traceback
import warnings
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import Any, NoReturn

from swarmshape.config import (
    DEFAULT_SHAPE,
    SETTINGS,
    CommandLine,
    RunConfig,
    configure,
    option_of,
)
from swarmshape.core.faults import FaultEvent, parse_event, parse_region
from swarmshape.core.options import FLAG, PLUGIN_KINDS, Spec, plain, specs
from swarmshape.errors import InputError, SettingError, SettingWarning
from swarmshape.io.files import remove_temporaries
from swarmshape.runs import resume
from swarmshape.session import Outputs, Session, preview, preview_text

COMMANDS = ("run", "edit", "sweep", "plot", "strategies", "check", "benchmark")
NOT_FORMED = 3
"""Exit status of a headless run that stopped before its shape formed (and of a failed check)."""
FLAGGED = tuple(spec for spec in SETTINGS if spec.extra.get("flag", True))
"""Run settings that are command-line flags (``--max-speed``); the others the command line
spells its own way: the shape is the path, faults are --fail, --fail-region and --stall, and a
plug-in's options are --set."""


class Parser(argparse.ArgumentParser):
    """argparse, but a mistake is one line on stderr like every other bad input."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"swarmshape: error: {_one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="swarmshape",
        description="Watch a swarm of square robots organise itself into a shape.",
        epilog="Commands: run (the default), edit, sweep, plot, strategies, check and benchmark. "
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
    listing = commands.add_parser(
        "strategies",
        help="list the available strategies, or one strategy's options",
        description="List every strategy, or with a NAME, what it reads and its options.",
    )
    listing.add_argument("name", nargs="?", help="a strategy, to list its options")
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
    bench = commands.add_parser(
        "benchmark",
        help="score a policy on the shape-formation-v1 tasks (needs the learn extra)",
        description="Run a policy on the benchmark's tasks and seeds; print its results as a "
        "Markdown table and its leaderboard row. Without a policy, list the tasks.",
    )
    bench.add_argument(
        "policy",
        nargs="?",
        help="random, learned, a local program (swarmshape strategies lists them), or "
        "path/to/file.py:Name or module:Name (a class, made with no arguments, or a policy)",
    )
    bench.add_argument("--tasks", help="task names, comma-separated (default: every task)")
    bench.add_argument(
        "--seeds", type=_seeds, help="seeds, e.g. 0-9 or 1,4,7 (default: each task's own)"
    )
    bench.add_argument("--json", type=Path, help="write the results as JSON to this file")
    bench.add_argument("--markdown", type=Path, help="write the results' table to this file")
    bench.add_argument("--force", action="store_true", help="let outputs replace files")
    return parser


def _seeds(text: str) -> list[int]:
    """``0-9``, ``1,4,7`` or both (``0-2,9``): seeds in the order given, each once."""
    seeds: list[int] = []
    for part in text.split(","):
        low, dash, high = part.strip().partition("-")
        try:
            first, last = int(low), int(high if dash else low)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected seeds like 0-9 or 1,4,7, got {text!r}"
            ) from None
        if not 0 <= first <= last < 2**63:
            raise argparse.ArgumentTypeError(
                f"seeds are whole numbers from 0 to 2**63 - 1, low-high ascending; got {part!r}"
            )
        if last - first >= 100_000:
            raise argparse.ArgumentTypeError(f"at most 100,000 seeds in a range, got {part!r}")
        seeds += [seed for seed in range(first, last + 1) if seed not in seeds]
    return seeds


def _shared_options() -> argparse.ArgumentParser:
    """Options of both run and edit; unset ones fall back to the scenario, then the defaults."""
    shared = Parser(add_help=False)
    groups = {"run": shared}
    for spec in FLAGGED:
        group = spec.extra.get("group", "run")
        if group not in groups:
            groups[group] = shared.add_argument_group(group)
        _add_flag(groups[group], spec)
    shared.add_argument(
        "--set",
        action="append",
        type=_option_text,
        metavar="NAME=VALUE",
        help="one of the strategy's own options (swarmshape strategies NAME lists them); "
        "repeatable",
    )
    image = groups["image loading"]
    image.add_argument(
        "--preview",
        action="store_true",
        help="print the shape as text beside its picture and stop (no run)",
    )
    sim = groups["simulation"]
    sim.add_argument("--speed", type=_speed, default=8, help="window: steps per frame (default 8)")
    sim.add_argument(
        "--load-state", type=Path, help="resume a run saved with --save-state (PATH not needed)"
    )
    faults = groups["faults"]
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


def _add_flag(parser: argparse._ActionsContainer, spec: Spec) -> None:
    """A run setting's flag: ``--max-speed X``, checked as the setting checks it."""
    flag = "--" + spec.name.replace("_", "-")
    default = "" if spec.default is None else f" (default {plain(spec.default)})"
    if spec.kind is FLAG:
        parser.add_argument(flag, action="store_true", default=None, help=spec.help)
        return

    def parse(text: str) -> Any:
        try:
            return spec.parse(text)
        except SettingError as error:
            raise argparse.ArgumentTypeError(error.problem) from None

    metavar = spec.kind.metavar if spec.choices is None else "{" + ",".join(spec.choices) + "}"
    parser.add_argument(flag, type=parse, metavar=metavar, help=f"{spec.help}{default}")


def settings_table() -> str:
    """The README's table of run settings, made from `RunConfig`'s declarations."""
    rows = ["| on the command line | in files | meaning |", "| --- | --- | --- |"]
    for spec in SETTINGS:
        flag = "--" + spec.name.replace("_", "-")
        if spec.kind is FLAG:
            cli = f"`{flag}`"
        elif spec in FLAGGED:
            # a bare | would split the table's cell, even inside a code span
            metavar = spec.kind.metavar if spec.choices is None else "\\|".join(spec.choices)
            cli = f"`{flag} {metavar}`"
        else:
            cli = spec.extra["cli"]
        files = spec.extra.get("files", f"`{spec.name}`")
        meaning = spec.help
        if spec.kind is not FLAG and spec.choices is None and spec.range_text():
            meaning += f"; {spec.describe()}"
        if spec.default not in (None, (), {}) and spec.kind is not FLAG:
            meaning += f"; default {plain(spec.default)}"
        if spec.readers != PLUGIN_KINDS:
            meaning += f"; read by {' and '.join(sorted(spec.readers))} plug-ins only"
        rows.append(f"| {cli} | {files} | {meaning} |")
    return "\n".join(rows)


def _option_text(text: str) -> tuple[str, CommandLine]:
    name, equals, value = text.partition("=")
    if not equals or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    return name.strip(), CommandLine(value)


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT, e.g. 60x40, got {text!r}"
        ) from None
    return width, height


def _speed(text: str) -> float:
    """Steps per frame: any number above 0 (the window takes the nearest of its speeds)."""
    try:
        speed = float(text)
    except ValueError:
        speed = math.nan
    if not 0 < speed < math.inf:
        raise argparse.ArgumentTypeError(f"steps per frame must be a number above 0, got {text!r}")
    return speed


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
    parser = build_parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown:
        parser.error(_unrecognised(unknown))
    flagged = {spec.name for spec in FLAGGED if getattr(args, spec.name, None) is not None}
    warnings.showwarning = _warnings_shown(flagged)
    _reuse_freed_memory()
    try:
        return COMMAND_FUNCTIONS[args.command](args)
    except InputError as error:
        print(f"swarmshape: error: {_one_line(_spelt(error, flagged))}", file=sys.stderr)
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
    finally:
        remove_temporaries()


def _unrecognised(unknown: list[str]) -> str:
    """argparse's complaint, or, for a plug-in's option given as a flag, how to give it."""
    for word in unknown:
        name = word.lstrip("-").partition("=")[0].replace("-", "_")
        if word.startswith("--") and option_of(name):
            return f"{word} is {option_of(name)}: give it as --set {name}=VALUE"
    return f"unrecognized arguments: {' '.join(unknown)}"


def _spelt(problem: SettingError | SettingWarning | Exception, flagged: set[str]) -> str:
    """A setting's message, naming its flag when the value came from the command line."""
    if isinstance(problem, SettingError | SettingWarning) and problem.setting in flagged:
        return f"--{problem.setting.replace('_', '-')} {problem.problem}"
    return str(problem)


def _warnings_shown(flagged: set[str]) -> Callable[..., None]:
    """How a command shows warnings: each as one line on stderr, like an error, without a
    source line below it. Of the shape's warnings only the first, which names the option that
    helps (a picture squeezed into one cell also has too many robots for it: raising --cells
    cures both); every setting that changes nothing is named."""
    shown: set[str] = set()

    def show(message: Warning | str, category: type, *_: object, **__: object) -> None:
        text = _spelt(message, flagged) if isinstance(message, Warning) else str(message)
        kind = text if category is SettingWarning else "shape"
        if kind not in shown:
            print(f"swarmshape: warning: {_one_line(text)}", file=sys.stderr)
            shown.add(kind)

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
    given = {spec.name: getattr(args, spec.name) for spec in FLAGGED}
    given["faults"] = fault_events(args)
    given["options"] = dict(args.set) if args.set else None
    if args.load_state is not None:
        _nothing_that_a_resume_ignores(args, given)
        config = RunConfig(**({} if args.max_steps is None else {"max_steps": args.max_steps}))
    else:
        config = configure(args.path, **given)
    if args.preview:
        if args.load_state is not None:  # the saved run's shape, not the default one
            print(preview_text(resume(args.load_state, args.strategy)[1].world))
        else:
            print(preview(config))
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
        # the fault events come from --fail, --stall and --fail-region
        flags = {"options": "--set", "faults": "--fail, --stall or --fail-region"}
        flag = flags.get(ignored[0], "--" + ignored[0].replace("_", "-"))
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
    from swarmshape.strategies import available, get

    if args.name is not None:
        print(describe_plugin(args.name, get(args.name)))
        return 0
    known = available()
    width = max(len(name) for name in known)
    for name, cls in sorted(known.items()):
        print(f"{name:<{width}}  {cls.kind:<7}  {cls.description}")
    return 0


def describe_plugin(name: str, cls: type) -> str:
    """A plug-in's kind, description and every option it takes, for ``strategies NAME``."""
    lines = [f"{name}  ({cls.kind})  {cls.description}"]
    if cls.grows_from_seeds:
        lines.append("forms only the part of a shape that is one piece with its seeds, no holes")
    if cls.enters_from_outside:
        lines.append(
            "a piece of a shape that only its pockets touch, beyond the sensing radius of the "
            "rest, fills only from robots there"
        )
    unread = [spec.name for spec in SETTINGS if cls.kind not in spec.readers]
    if unread:
        lines.append(f"does not read the run settings {', '.join(unread)}")
    options = specs(cls.Options)
    if not options:
        lines.append("takes no options")
        return "\n".join(lines)
    lines.append("options (--set NAME=VALUE; [options] in a scenario; options.NAME in a sweep):")
    width = max(len(spec.name) for spec in options)
    for spec in options:
        lines.append(f"  {spec.name:<{width}}  {spec.describe()}, default {plain(spec.default)}")
        if spec.help:
            lines.append(f"  {'':<{width}}  {spec.help}")
    return "\n".join(lines)


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


def run_benchmark(args: argparse.Namespace) -> int:
    try:
        from swarmshape.env import benchmark
    except ImportError as error:  # without the learn extra
        raise InputError(f"swarmshape benchmark: {error}") from None
    from swarmshape.io.files import check_output, distinct_outputs, write_text

    chosen = benchmark.tasks(args.tasks)
    if args.policy is None:
        print(benchmark.suite.table(chosen), end="")
        return 0
    outputs = [(flag, path) for flag, path in (("--json", args.json),
               ("--markdown", args.markdown)) if path is not None]  # fmt: skip
    for flag, path in outputs:
        check_output(path, flag, may_replace=args.force)
    distinct_outputs(outputs)
    policy = benchmark.policy(args.policy)

    def progress(task: str, seconds: float) -> None:
        print(f"swarmshape: {task} done in {seconds:,.0f} s", file=sys.stderr)

    results = benchmark.evaluate(policy, chosen, args.seeds, progress)
    table = benchmark.to_markdown(results)
    print(table)
    print(benchmark.leaderboard([results]), end="")
    if args.json is not None:
        write_text(args.json, benchmark.to_json(results))
    if args.markdown is not None:
        write_text(args.markdown, table)
    return 0


COMMAND_FUNCTIONS = {
    "run": run_session,
    "edit": run_session,
    "sweep": run_sweep,
    "plot": run_plot,
    "strategies": list_strategies,
    "check": run_check,
    "benchmark": run_benchmark,
}

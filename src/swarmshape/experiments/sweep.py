"""Parameter sweeps: the cross product of a TOML file's lists, run in parallel, one CSV row each.

    shapes = ["../shapes/horseshoe.png"]        # relative to the sweep file
    strategies = ["paper", "greedy", "optimal"]
    agents = [50, 90, 150]                        # 0 means one per cell
    seeds = 3                                     # a count (0, 1, 2) or a list
    cells = 32                                    # any further run option, one value or a list
    msg_loss = [0, 0.1, 0.3]                      # noise: msg_loss, distance_noise, ...
    max_steps = 200000

Every key but `seeds` may hold one value or a list; each combination runs once per seed.
A sweep holds at most `MAX_RUNS` runs. Runs go to local processes, or with a Dask address to
a Dask cluster. Each finished run is added to the CSV at once (see `results`), so a killed
sweep resumes where it stopped: rows whose ``run`` key is already there are skipped. At the
end the rows are sorted by their settings.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmshape.config import SETTINGS, RunConfig, configure, option_of
from swarmshape.core.faults import parse_event, parse_region
from swarmshape.core.metrics import run_metrics
from swarmshape.core.options import Spec
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import START_LAYOUTS
from swarmshape.errors import InputError
from swarmshape.experiments.progress import ProgressBar
from swarmshape.experiments.results import open_results
from swarmshape.io.files import read_toml
from swarmshape.runs import (
    Observer,
    build,
    files_read,
    load_world,
    one_per_world,
    registered_strategy,
    run,
)

SEEDS = "a count of at least 1, or a list of seeds from 0 to 2**63 - 1"
OWN_KEYS = {
    "shapes": ("a file name", lambda v: isinstance(v, str) and v != ""),
    "strategies": ("a strategy name", lambda v: isinstance(v, str) and v != ""),
    "agents": ("a whole number (0: one per cell)", lambda v: _whole(v) and v >= 0),
    "curve_every": ("a whole number of at least 1", lambda v: _whole(v) and v >= 1),
    "start": ("packed or scatter", lambda v: v in START_LAYOUTS),
    "fail": ("AMOUNT@STEP text such as '0.2@300' (robots removed at random)", lambda v: _fault(v)),
    "stall": ("AMOUNT@STEP text such as '0.1@300' (robots stalled)", lambda v: _fault(v)),
    "fail_region": ("X,Y,W,H@STEP text such as '4,4,6,6@300'", lambda v: _region(v)),
}
"""Keys a sweep spells its own way: plural names, robots counted from 0, layouts by name only,
one fault event per key, and the coverage curve's sampling."""
KINDS: dict[str, tuple[str, Callable[[Any], bool]]] = {
    **{
        spec.name: (spec.describe(), lambda v, spec=spec: _accepted(spec, v))
        for spec in SETTINGS
        if spec.name not in ("shape", "strategy", "seed", "faults", "options")
    },
    **OWN_KEYS,
}
"""Every key a sweep file may have but `seeds` and ``options.NAME``, with what each of its
values must be: the run settings and the sweep's own keys."""
FAULT_KEYS = ("fail", "stall", "fail_region")
"""Sweep keys that each make one fault event of a run (a list of them: one run per value)."""
OPTION = "options."
"""A plug-in option's key in a run's settings and the results: ``options.order``."""
INTERRUPTED = 130
"""Exit status after Ctrl+C, as a shell reports it."""
CURVE_EVERY = 10
"""Steps between the coverage samples each row keeps for coverage-over-time plots."""
MAX_RUNS = 100_000
"""The most runs one sweep may ask for: more is surely a slip (``seeds = 100000`` with twelve
combinations), and would take weeks; split a real one into several sweep files."""
WATCH = 0.25
"""Seconds between a worker's looks at whether its sweep is still there."""
DASK_RUNNING = 1000
"""Runs submitted to a Dask cluster at a time: enough to keep a large one busy."""


@dataclass(frozen=True)
class Sweep:
    """The runs of a sweep file: every combination of its values, once per seed. Runs are made
    one at a time as they are needed, as a list they could fill the memory."""

    values: dict[str, list]
    """Each run option (``shape``, ``strategy``, ``agents``, ...) and its values."""
    seeds: Sequence[int]

    @property
    def count(self) -> int:
        # len() of a range fails past 2**63 seeds, which are to be refused, not crashed on
        seeds = self.seeds.stop if isinstance(self.seeds, range) else len(self.seeds)
        return math.prod(len(values) for values in self.values.values()) * seeds

    def __len__(self) -> int:
        return self.count

    def __iter__(self) -> Iterator[dict[str, Any]]:
        names = sorted(self.values)
        for combination in itertools.product(*(self.values[name] for name in names)):
            config = dict(zip(names, combination, strict=True))
            for seed in self.seeds:
                yield {**config, "seed": seed}


def read_sweep(path: Path) -> Sweep:
    """The runs the sweep file asks for, every value checked (shapes loaded) before any run,
    so that a mistake is reported at once and not by the hundredth run."""
    path = Path(path)
    data = _read_toml(path)
    unknown = sorted(set(data) - set(KINDS) - {"seeds", "options"})
    if unknown:
        expected = ", ".join(sorted({*KINDS, "seeds", "options.NAME"}))
        hint = ""
        if option_of(unknown[0]):
            hint = f" ({unknown[0]} is {option_of(unknown[0])}: write options.{unknown[0]})"
        raise InputError(f"{path}: unknown key {unknown[0]!r}{hint}; expected one of {expected}")
    for key in ("shapes", "strategies"):
        if key not in data:
            raise InputError(f"{path}: needs {key} = [...]")
    values = {"agents": [0], "cells": [RunConfig.cells], "max_steps": [RunConfig.max_steps]}
    for key, value in data.items():
        if key == "options":
            values |= _option_values(path, value)
        elif key != "seeds":
            name = {"shapes": "shape", "strategies": "strategy"}.get(key, key)
            kind, fits = KINDS[key]
            values[name] = _values(path, key, value, f"{kind}, or a list of them", fits)
    runs = Sweep(values, _seeds(path, data.get("seeds", 1)))
    if runs.count > MAX_RUNS:
        raise InputError(
            f"{path}: asks for {runs.count:,} runs, more than the {MAX_RUNS:,} one sweep may "
            "hold; split it into several sweep files"
        )
    _check_runs(path, values)
    return runs


def _read_toml(path: Path) -> dict[str, Any]:
    """The sweep file's table. Only a regular file is read: a pipe would hang the sweep, and
    a device such as /dev/zero fill the memory."""
    if not os.path.exists(path):  # False, not an error, for a name too long to look up
        raise InputError(f"{path}: no such sweep file")
    return read_toml(path, "a sweep .toml file")


def _values(path: Path, key: str, value: Any, kind: str, fits: Callable[[Any], bool]) -> list:
    """A key's values as a list (one value or a list of them), each `fits`, none twice (a
    repeated value would run the same runs twice). A list that is itself one value (an
    arena's [width, height]) is one value."""
    values = [value] if not isinstance(value, list) or fits(value) else value
    if not values:
        raise InputError(f"{path}: {key} is an empty list; give it at least one value")
    seen = []
    for item in values:
        if not fits(item):
            raise InputError(f"{path}: {key} must be {kind}; got {item!r}")
        if item in seen:
            raise InputError(f"{path}: {key} lists {item!r} twice")
        seen.append(item)
    return values


def _option_values(path: Path, table: Any) -> dict[str, list]:
    """``options.NAME = value or [values]``: each a key of the cross product, checked against
    the strategies' options once the runs are known (see `_check_runs`)."""
    if not isinstance(table, dict):
        raise InputError(f"{path}: options must be a table: options.NAME = [values]")
    plain = ("a plain value", lambda v: isinstance(v, bool | int | float | str))
    return {
        OPTION + name: _values(path, OPTION + name, value, "a value or a list of them", plain[1])
        for name, value in table.items()
    }


def _seeds(path: Path, seeds: Any) -> Sequence[int]:
    """A count n is the seeds 0 to n - 1."""
    if not _whole(seeds):
        return _values(path, "seeds", seeds, SEEDS, lambda v: _whole(v) and 0 <= v < 2**63)
    if seeds < 1:
        raise InputError(f"{path}: seeds must be {SEEDS}; got {seeds!r}")
    return range(seeds)


WORLD_KEYS = ("shape", "cells", "agents", "threshold", "invert", "fit", "arena", "start")
"""The sweep keys that decide a run's world (`load_world` reads them), with the strategy."""


def _check_runs(path: Path, values: dict[str, list]) -> None:
    """What only a run's description or its world can tell: strategies and their options,
    speed limits, images, scenarios, robot counts and arenas (checked once per distinct
    combination; a world built for one strategy of each kind, growing from its seeds or not).
    Checked for shapes, cells and robots alone, an arena too small for one shape ended a
    sweep after the runs before it."""
    options = [name for name in values if name.startswith(OPTION)]
    try:
        for strategy in values["strategy"]:
            registered_strategy(strategy)
            for combination in itertools.product(*(values[name] for name in options)):
                chosen = {
                    name[len(OPTION) :]: v for name, v in zip(options, combination, strict=True)
                }
                RunConfig(strategy=strategy, options=chosen)
        for speed, accel in itertools.product(
            values.get("max_speed", [RunConfig.max_speed]),
            values.get("max_accel", [RunConfig.max_accel]),
        ):
            RunConfig(max_speed=speed, max_accel=accel)
        keys = [key for key in WORLD_KEYS if key in values]
        for strategy in one_per_world(values["strategy"]):
            for combination in itertools.product(*(values[key] for key in keys)):
                world = dict(zip(keys, combination, strict=True))
                shape, agents = path.parent / world.pop("shape"), world.pop("agents") or None
                load_world(configure(shape, strategy=strategy, agents=agents, **world))
    except InputError as error:
        raise InputError(f"{path}: {error}") from None


def _fault(value: Any) -> bool:
    try:
        return isinstance(value, str) and bool(parse_event(value, "remove", "fail"))
    except InputError:
        return False


def _region(value: Any) -> bool:
    try:
        return isinstance(value, str) and bool(parse_region(value))
    except InputError:
        return False


def _accepted(spec: Spec, value: Any) -> bool:
    """Whether `value` is one the run setting `spec` accepts (its own check decides)."""
    try:
        spec.check(value)
    except InputError:
        return False
    return True


def fault_options(config: dict[str, Any]) -> dict[str, Any]:
    """A sweep row's fault keys as run options: one event per key given."""
    events = []
    for key in FAULT_KEYS:
        if config.get(key) is not None:
            text = config[key]
            if key == "fail_region":
                events.append(parse_region(text))
            else:
                events.append(parse_event(text, "stall" if key == "stall" else "remove", key))
    return {"faults": tuple(events)} if events else {}


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def files_read_by(runs: Collection[dict[str, Any]], base: Path) -> dict[Path, str]:
    """Every file the runs read (shape paths relative to `base`): a sweep's results file may
    replace none of them, even with --force. The fuzz named a sweep's own shape as its --out,
    with --force, and the sweep wrote its rows over the picture."""
    found: dict[Path, str] = {}
    for shape, strategy in {(config["shape"], config["strategy"]) for config in runs}:
        found |= files_read(configure(base / shape, strategy=strategy))
    return found


def run_key(config: dict[str, Any]) -> str:
    """A stable name for one run, to skip it when a sweep resumes."""
    return json.dumps(config, sort_keys=True)


def run_one(config: dict[str, Any], base: Path) -> dict[str, Any]:
    """One headless run (shape paths relative to `base`); its CSV row: config, every metric,
    coverage curve, wall time."""
    started = time.perf_counter()
    skip = ("shape", "agents", "curve_every", *FAULT_KEYS)
    settings = {k: v for k, v in config.items() if k not in skip and not k.startswith(OPTION)}
    options = {k[len(OPTION) :]: v for k, v in config.items() if k.startswith(OPTION)}
    run_config = configure(
        base / config["shape"],
        agents=config["agents"] or None,
        options=options,
        **settings | fault_options(config),
    )
    curve = CoverageCurve(config.get("curve_every", CURVE_EVERY))
    swarm = run(build(run_config), [curve], run_config.max_steps)
    metrics = run_metrics(swarm)
    scalars = {k: v for k, v in metrics.items() if not isinstance(v, list | dict)}
    recoveries = [fault["recovery_steps"] for fault in metrics["faults"]]
    scalars["recovery_steps"] = None if None in recoveries else max(recoveries, default=None)
    return {
        "run": run_key(config),
        **{f"config.{k}": v for k, v in sorted(config.items())},
        **scalars,
        "curve_every": curve.every,
        "coverage_curve": json.dumps(curve.values),
        "wall_time": round(time.perf_counter() - started, 3),
    }


class CoverageCurve(Observer):
    """Coverage every `every` steps and where the run ended: an observer for one sweep row."""

    def __init__(self, every: int) -> None:
        self.every = every
        self.values: list[float] = []

    def capture(self, swarm: Swarm) -> None:
        if swarm.step_count % self.every == 0:
            self.values.append(round(float(swarm.filled.mean()), 4))

    def close(self, swarm: Swarm) -> None:
        if swarm.step_count % self.every:
            self.values.append(round(float(swarm.filled.mean()), 4))


def run_sweep_file(
    path: Path, out: Path | None, *, dask: str | None, workers: int | None, force: bool = False
) -> int:
    """``swarmshape sweep``: run what the file asks for that `out` lacks, with a progress bar.
    `force` lets `out` replace a file that is not this sweep's results."""
    runs = read_sweep(path)
    out = out or path.with_suffix(".csv")
    bar = ProgressBar()
    try:
        ran = sweep(
            runs,
            out,
            path.parent,
            dask=dask,
            workers=workers,
            force=force,
            progress=lambda done, total: bar.show(done / total, f"{done}/{total} runs", now=True),
            reads={path: "the sweep file"},
        )
    except KeyboardInterrupt:
        bar.done()
        message = f"interrupted; finished runs are kept in {out}: run the same command to go on"
        print(f"swarmshape: {message}", file=sys.stderr)
        return INTERRUPTED
    bar.done()
    print(f"{ran} runs done now, {len(runs) - ran} were there already; the results are in {out}")
    return 0


def sweep(
    runs: Collection[dict[str, Any]],
    out: Path,
    base: Path,
    *,
    dask: str | None = None,
    workers: int | None = None,
    force: bool = False,
    progress: Callable[[int, int], None] | None = None,
    reads: Mapping[Path, str] | None = None,
) -> int:
    """Run what `out` does not have yet (shape paths are relative to `base`), each row added
    as its run ends; return how many ran. `out` is checked before any run (see
    `open_results`); `force` lets it replace a file that is not results of these settings,
    but none the runs read nor any of `reads` (path: what it is, e.g. the sweep file)."""
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    first = next(iter(runs), None)
    if first is None:
        return 0
    settings = [f"config.{name}" for name in sorted(first)]
    inputs = files_read_by(runs, base) | dict(reads or {})
    keys = {run_key(config) for config in runs}
    with open_results(out, settings, runs=keys, force=force, inputs=inputs) as results:
        already = sum(run_key(config) in results.done for config in runs)
        todo = (config for config in runs if run_key(config) not in results.done)
        finished = 0

        def add(row: dict[str, Any]) -> None:
            nonlocal finished
            results.add(row)
            finished += 1
            if progress:
                progress(already + finished, len(runs))

        if already < len(runs):
            if dask is not None:
                _on_dask(todo, base, dask, add)
            else:
                left = len(runs) - already
                _on_processes(todo, base, min(workers or _cores(), _cores(), left), add)
        results.finish()
    return finished


def _on_processes(
    todo: Iterator[dict[str, Any]],
    base: Path,
    workers: int,
    add: Callable[[dict[str, Any]], None],
) -> None:
    """Run on local processes; runs are handed out two per worker at most, the rest wait in
    `todo` (not in memory). On Ctrl+C or an error the runs under way are ended at once."""
    with ProcessPoolExecutor(workers, initializer=_worker_setup, initargs=(os.getpid(),)) as pool:
        running: set[Future] = set()
        try:
            while True:
                for config in itertools.islice(todo, 2 * workers - len(running)):
                    running.add(pool.submit(run_one, config, base))
                if not running:
                    return
                finished, running = wait(running, return_when=FIRST_COMPLETED)
                for future in finished:
                    add(future.result())
        except BaseException:
            processes = list(pool._processes.values())  # public only in Python 3.14
            pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.terminate()
            raise


def _cores() -> int:
    """Cores this process may use: runs are CPU-bound, more workers only share them."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _worker_setup(sweep_pid: int) -> None:
    """First thing in each pool worker: leave Ctrl+C to the sweep (a terminal sends it to the
    workers too, and they would print tracebacks), and die with the sweep, even one killed
    with kill -9 (its workers would otherwise run on for hours, unseen)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    parent = os.getppid()  # the sweep, or a fork server that ends with it
    threading.Thread(target=_exit_with, args=(parent, sweep_pid), daemon=True).start()


def _exit_with(parent: int, sweep_pid: int) -> None:
    """Exit when the worker's parent is gone (the worker is handed to another), or the sweep
    is (it may have died before the worker started)."""
    while os.getppid() == parent and _alive(sweep_pid):
        time.sleep(WATCH)
    os._exit(1)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # a process of another user: it exists
    return True


def _on_dask(
    todo: Iterator[dict[str, Any]],
    base: Path,
    address: str,
    add: Callable[[dict[str, Any]], None],
) -> None:
    """Run on a Dask cluster; at most `DASK_RUNNING` runs are submitted at a time."""
    try:
        from dask.distributed import Client
        from dask.distributed import as_completed as dask_completed
    except ImportError:
        message = "--dask needs the cluster extra: pip install 'swarmshape[cluster]'"
        raise InputError(message) from None
    try:
        client = Client(address, timeout=10)
    except OSError as error:
        raise InputError(f"cannot reach the Dask scheduler at {address} ({error})") from None
    except (ValueError, TypeError) as error:  # what Dask makes of a malformed address
        message = f"--dask {address!r} is not the address of a Dask scheduler ({error})"
        raise InputError(message) from None
    base = base.resolve()  # the cluster's workers may run elsewhere
    with client:

        def submit(config: dict[str, Any]):
            return client.submit(run_one, config, base=base, pure=False)

        running = dask_completed([submit(c) for c in itertools.islice(todo, DASK_RUNNING)])
        for future in running:
            add(future.result())
            for config in itertools.islice(todo, 1):
                running.add(submit(config))

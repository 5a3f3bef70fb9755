"""Parameter sweeps: the cross product of a TOML file's lists, run in parallel, one CSV row each.

    shapes = ["../shapes/horseshoe.png"]        # relative to the sweep file
    strategies = ["paper", "greedy", "optimal"]
    agents = [50, 90, 150]                        # 0 means one per cell
    seeds = 3                                     # a count (0, 1, 2) or a list
    cells = 32                                    # any further run option, one value or a list
    max_steps = 200000

Every key but `seeds` may hold one value or a list; each combination runs once per seed.
Runs go to local processes, or with a Dask address to a Dask cluster. Each finished run is
appended to the CSV at once, so a killed sweep resumes where it stopped: rows whose ``run``
key is already there are skipped. At the end the file is rewritten in a stable order.
"""

from __future__ import annotations

import csv
import itertools
import json
import os
import time
import tomllib
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from io import StringIO
from pathlib import Path
from typing import Any

from swarmshape.core.metrics import run_metrics
from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.experiments.progress import ProgressBar
from swarmshape.io.files import write_text
from swarmshape.runs import RunConfig, build, configure, run

OPTIONS = {"shapes", "strategies", "agents", "seeds", "cells", "max_steps", "order",
           "max_speed", "max_accel", "curve_every"}  # fmt: skip
CURVE_EVERY = 10
"""Steps between the coverage samples each row keeps for coverage-over-time plots."""


def read_sweep(path: Path) -> list[dict[str, Any]]:
    """Every run the sweep file asks for, as a plain dict (with its seed)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: no such sweep file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: not valid TOML ({error})") from None
    unknown = sorted(set(data) - OPTIONS)
    if unknown:
        expected = ", ".join(sorted(OPTIONS))
        raise InputError(f"{path}: unknown key {unknown[0]!r}; expected one of {expected}")
    for key in ("shapes", "strategies"):
        if not data.get(key):
            raise InputError(f"{path}: needs {key} = [...]")
    seeds = data.pop("seeds", 1)
    seeds = list(range(seeds)) if isinstance(seeds, int) else seeds
    if not isinstance(seeds, list) or not all(isinstance(s, int) for s in seeds):
        raise InputError(f"{path}: seeds must be a count or a list of integers")
    defaults = RunConfig()
    recorded = {"cells": defaults.cells, "max_steps": defaults.max_steps, "order": defaults.order}
    values = {"agents": 0, **recorded, **data}
    names = sorted(values)
    runs = []
    for combination in itertools.product(*(_listed(values[name]) for name in names)):
        for seed in seeds:
            config = dict(zip(names, combination, strict=True))
            config["shape"] = config.pop("shapes")
            config["strategy"] = config.pop("strategies")
            runs.append({**config, "seed": seed})
    return runs


def _listed(value: Any) -> list:
    return value if isinstance(value, list) else [value]


def run_key(config: dict[str, Any]) -> str:
    """A stable name for one run, to skip it when a sweep resumes."""
    return json.dumps(config, sort_keys=True)


def run_one(config: dict[str, Any], base: Path) -> dict[str, Any]:
    """One headless run (shape paths relative to `base`); its CSV row: config, every metric,
    coverage curve, wall time."""
    started = time.perf_counter()
    options = {k: v for k, v in config.items() if k not in ("shape", "agents", "curve_every")}
    run_config = configure(base / config["shape"], agents=config["agents"] or None, **options)
    curve = CoverageCurve(config.get("curve_every", CURVE_EVERY))
    swarm = run(build(run_config), [curve], run_config.max_steps)
    metrics = run_metrics(swarm)
    scalars = {k: v for k, v in metrics.items() if not isinstance(v, list | dict)}
    return {
        "run": run_key(config),
        **{f"config.{k}": v for k, v in sorted(config.items())},
        **scalars,
        "curve_every": curve.every,
        "coverage_curve": json.dumps(curve.values),
        "wall_time": round(time.perf_counter() - started, 3),
    }


class CoverageCurve:
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


def run_sweep_file(path: Path, out: Path | None, *, dask: str | None, workers: int | None) -> int:
    """``swarmshape sweep``: run what the file asks for that `out` lacks, with a progress bar."""
    runs = read_sweep(path)
    out = out or path.with_suffix(".csv")
    bar = ProgressBar()
    ran = sweep(
        runs,
        out,
        path.parent,
        dask=dask,
        workers=workers,
        progress=lambda done, total: bar.show(done / total, f"{done}/{total} runs", now=True),
    )
    bar.done()
    print(f"{out}: {ran} runs done now, {len(runs) - ran} were there already")
    return 0


def sweep(
    runs: list[dict[str, Any]],
    out: Path,
    base: Path,
    *,
    dask: str | None = None,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> int:
    """Run what `out` does not have yet (shape paths are relative to `base`); return how
    many ran."""
    done = {row["run"] for row in read_rows(out)}
    todo = [config for config in runs if run_key(config) not in done]
    finished = 0
    for row in _on_dask(todo, base, dask) if dask else _on_processes(todo, base, workers):
        _append(out, row)
        finished += 1
        if progress:
            progress(len(done) + finished, len(runs))
    _rewrite_sorted(out)
    return finished


def _on_processes(
    todo: list[dict[str, Any]], base: Path, workers: int | None
) -> Iterator[dict[str, Any]]:
    if not todo:
        return
    with ProcessPoolExecutor(max_workers=workers or os.cpu_count()) as pool:
        for future in as_completed([pool.submit(run_one, config, base) for config in todo]):
            yield future.result()


def _on_dask(todo: list[dict[str, Any]], base: Path, address: str) -> Iterator[dict[str, Any]]:
    try:
        from dask.distributed import Client
        from dask.distributed import as_completed as dask_completed
    except ImportError:
        message = "--dask needs the cluster extra: pip install 'swarmshape[cluster]'"
        raise InputError(message) from None
    if not todo:
        return
    try:
        client = Client(address, timeout=10)
    except OSError as error:
        raise InputError(f"cannot reach the Dask scheduler at {address} ({error})") from None
    with client:
        futures = client.map(run_one, todo, base=base.resolve(), pure=False)
        for future in dask_completed(futures):
            yield future.result()


def read_rows(path: Path) -> list[dict[str, str]]:
    if not Path(path).exists():
        return []
    with Path(path).open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def _append(path: Path, row: dict[str, Any]) -> None:
    """One finished run, written and flushed straight away (a kill loses only running ones)."""
    fresh = not Path(path).exists() or Path(path).stat().st_size == 0
    with Path(path).open("a", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(row))
        if fresh:
            writer.writeheader()
        writer.writerow(row)
        handle.flush()
        os.fsync(handle.fileno())


def _rewrite_sorted(path: Path) -> None:
    rows = read_rows(path)
    if not rows:
        return
    rows.sort(key=lambda row: row["run"])
    lines = [list(rows[0])] + [list(row.values()) for row in rows]
    write_text(path, _csv_text(lines))


def _csv_text(lines: Iterable[list]) -> str:
    buffer = StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(lines)
    return buffer.getvalue()

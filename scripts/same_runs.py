"""Record a table of runs, or check that today's code still gives the same ones, bit for bit.

    .venv/bin/python scripts/same_runs.py record runs.json [--only NAME ...] [--workers 2]
    .venv/bin/python scripts/same_runs.py compare runs.json [--only NAME ...] [--workers 2]

A change that should not change behaviour (a faster step, a tidier phase) must leave every run
as it was. Each run goes through the command line as a user's would (`swarmshape PNG
--headless ...`), in its own process, and keeps its `--metrics` JSON and a digest of every
robot's position and state at every step (`--positions`), so a change that moves one robot
one step differently shows up even when the metrics happen to agree. The table covers every
built-in strategy, several shipped shapes, faults (removals, stalls, a failure rate), noise on
local programs' senses, speed variation, two groups, a 10,000-robot run, and a run resumed
from a checkpoint. `compare` prints the runs that differ and exits 1 if any does.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "shapes"
NOT_FORMED = 3
"""The exit code of a run that stopped before its shape formed (a saved run's first part)."""
SEEDED = ["--seed", "1"]
NOISE = ["--msg-loss", "0.1", "--distance-noise", "0.1"]

RUNS: dict[str, list[str]] = {
    "optimal-block": ["block.png", "--cells", "50"],
    "optimal-star": ["star.png", "--cells", "40"],
    "optimal-horse": ["horse.png", "--cells", "40"],
    "optimal-ring-fail": ["ring.png", "--cells", "40", "--fail", "0.2@50"],
    "optimal-letter-10k": ["letter-s.png", "--cells", "142"],
    "optimal-horseshoe-stall": ["horseshoe.png", "--stall", "0.05@20"],
    "optimal-star-variation": ["star.png", "--cells", "30", "--speed-variation", "0.5"],
    "greedy-horse": ["horse.png", "--cells", "40", "--strategy", "greedy"],
    "greedy-square-fail": ["square.png", "--strategy", "greedy", "--fail", "0.2@50"],
    "greedy-star-rate": ["star.png", "--cells", "30", "--strategy", "greedy",
                         "--failure-rate", "0.001"],
    "random-letter-k": ["letter-k.png", "--cells", "30", "--strategy", "random"],
    "random-block-stall": ["block.png", "--cells", "30", "--strategy", "random",
                           "--stall", "0.05@10"],
    "paper-star": ["star.png", "--cells", "16", "--strategy", "paper"],
    "paper-horseshoe-fail": ["horseshoe.png", "--strategy", "paper", "--fail", "0.2@50"],
    "paper-two-squares": ["two-squares.toml"],
    "self-assembly-square": ["small-square.png", "--strategy", "self-assembly"],
    "self-assembly-noise": ["small-square.png", "--strategy", "self-assembly", *NOISE],
    "local-swap-letter": ["letter-s.png", "--cells", "24", "--strategy", "local-swap"],
    "local-swap-noise": ["letter-k.png", "--cells", "16", "--strategy", "local-swap", *NOISE],
    "local-swap-fail": ["letter-s.png", "--cells", "20", "--strategy", "local-swap",
                        "--fail", "0.2@50"],
    "mean-shift-letter": ["letter-s.png", "--cells", "24", "--strategy", "mean-shift"],
    "mean-shift-noise": ["letter-k.png", "--cells", "16", "--strategy", "mean-shift", *NOISE],
    "mean-shift-fail": ["star.png", "--cells", "24", "--strategy", "mean-shift",
                        "--fail", "0.2@50", "--agents", "300"],
    "mean-shift-ring": ["ring.png", "--cells", "30", "--strategy", "mean-shift"],
    "optimal-agents": ["ring.png", "--cells", "30", "--agents", "900", "--start", "packed"],
}  # fmt: skip
RESUMED = {
    "optimal-star-resumed": ("optimal-star", 60),
    "local-swap-resumed": ("local-swap-letter", 200),
}
"""Runs saved at a step (`--max-steps`, `--save-state`) and resumed (`--load-state`)."""


def swarmshape(arguments: list[str], folder: Path, name: str) -> dict:
    """One run from the shell: its metrics and a digest of its positions and states."""
    metrics, positions = folder / f"{name}.json", folder / f"{name}.npz"
    command = [str(Path(sys.executable).parent / "swarmshape"), *arguments]
    command += ["--headless", "--force"]
    command += ["--metrics", str(metrics), "--positions", str(positions)]
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, cwd=SHAPES)
    if done.returncode not in (0, NOT_FORMED):
        raise SystemExit(f"{name}: {' '.join(command)} failed:\n{done.stderr}")
    digest = hashlib.sha256()
    with np.load(positions) as saved:
        for key in ("step", "position", "state", "group"):
            digest.update(np.ascontiguousarray(saved[key]).tobytes())
    return {
        "arguments": arguments,
        "metrics": json.loads(metrics.read_text()),
        "positions": digest.hexdigest(),
        "seconds": round(time.perf_counter() - started, 2),
    }


def run_one(name: str, folder: Path) -> dict:
    if name not in RESUMED:
        return swarmshape([*RUNS[name], *SEEDED, "--max-steps", "20000"], folder, name)
    base, at = RESUMED[name]
    state = folder / f"{name}.state"
    saving = [*RUNS[base], *SEEDED, "--max-steps", str(at), "--save-state", str(state)]
    swarmshape(saving, folder, name)
    return swarmshape(["--load-state", str(state)], folder, name)


def run_all(names: list[str], workers: int) -> dict[str, dict]:
    with tempfile.TemporaryDirectory() as scratch, ThreadPoolExecutor(workers) as pool:
        folder = Path(scratch)
        found = dict(zip(names, pool.map(lambda name: run_one(name, folder), names), strict=True))
    for name, row in found.items():
        print(f"  {name:<28} {row['metrics']['steps']!s:>6} steps  {row['seconds']:6.1f} s")
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=["record", "compare"])
    parser.add_argument("file", type=Path, help="the recorded table (JSON)")
    parser.add_argument("--only", nargs="+", help="just these runs")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    every = [*RUNS, *RESUMED]
    names = args.only or every
    if unknown := sorted(set(names) - set(every)):
        parser.error(f"no such run: {', '.join(unknown)}")
    if args.action == "record":
        found = run_all(names, args.workers)
        args.file.write_text(json.dumps(found, indent=1) + "\n")
        print(f"recorded {len(found)} runs in {args.file}")
        return
    recorded = json.loads(args.file.read_text())
    if missing := [name for name in names if name not in recorded]:
        parser.error(f"not recorded in {args.file}: {', '.join(missing)}")
    found = run_all(names, args.workers)
    differ = [
        name
        for name in names
        if (found[name]["metrics"], found[name]["positions"])
        != (recorded[name]["metrics"], recorded[name]["positions"])
    ]
    for name in differ:
        was, now = recorded[name]["metrics"], found[name]["metrics"]
        changed = {
            key: (was.get(key), now.get(key)) for key in was | now if was.get(key) != now.get(key)
        }
        print(f"DIFFERS {name}: {changed or 'positions only'}")
    before = sum(recorded[name]["seconds"] for name in names)
    after = sum(found[name]["seconds"] for name in names)
    print(
        f"{len(names) - len(differ)} of {len(names)} runs the same;"
        f" {before:.0f} s then, {after:.0f} s now"
    )
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()

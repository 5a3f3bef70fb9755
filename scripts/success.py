"""Success rate per setting of a sweep's results: the share of seeds that formed the shape.

python scripts/success.py sweeps/self-assembly-noise.csv --iou 0.9

A run succeeds when it formed its shape (every target filled but those lost to stalled
robots: its ``steps`` column is set) or, with ``--iou``, its IoU reaches that value (a program
that grows from its seeds may form an imperfect shape: Rubenstein et al.'s measure).
One line per setting (every ``config.`` column but the seed): runs, successes, steps and IoU.
"""

from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

from swarmshape.errors import InputError
from swarmshape.experiments.results import read_rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--iou", type=float, help="count a run with at least this IoU a success")
    args = parser.parse_args()
    try:
        rows = read_rows(args.results)
    except InputError as error:
        print(f"success.py: error: {error}", file=sys.stderr)
        return 2
    if not rows:
        print(f"success.py: error: {args.results}: no runs in it yet", file=sys.stderr)
        return 2
    varied = [
        name
        for name in rows[0]
        if name.startswith("config.") and name != "config.seed"
        and len({row[name] for row in rows}) > 1
    ]  # fmt: skip
    settings = defaultdict(list)
    for row in rows:
        settings[tuple(row[name] for name in varied)].append(row)
    names = [name.removeprefix("config.") for name in varied]
    print("  ".join(f"{name:>14}" for name in names), " runs  formed   steps (min-max)   IoU min")
    for setting, runs in sorted(settings.items()):
        formed = sum(_formed(row, args.iou) for row in runs)
        steps = [int(row["steps_run"]) for row in runs]
        iou = min(float(row["iou"]) for row in runs)
        spread = f"{min(steps):>6,}-{max(steps):<7,}"
        shown = "  ".join(f"{value:>14}" for value in setting)
        print(shown, f"{len(runs):5}  {formed:3}/{len(runs):<3}  {spread}  {iou:7.3f}")
    return 0


def _formed(row: dict[str, str], iou: float | None) -> bool:
    return row["steps"] != "" or (iou is not None and float(row["iou"]) >= iou)


if __name__ == "__main__":
    sys.exit(main())

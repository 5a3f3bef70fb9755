"""A Markdown table comparing strategies from sweeps' results, one row per shape, robot count
and strategy (every other varied setting too), so that a table in the docs is made, not typed.

python scripts/compare.py sweeps/mean-shift.csv sweeps/mean-shift-fig4.csv
python scripts/compare.py --update docs/mean-shift.md

With ``--update FILE``, every block of FILE between ``<!-- compare: CSV ... -->`` and
``<!-- /compare -->`` is replaced by the table of those CSVs (paths from the repository's
root), so the tables in the docs are remade, never typed.

Columns: runs; formed (every target filled, its ``steps`` column set); steps to form, and their
ratio to the makespan lower bound, as the median and range over the runs that formed; the
least-distance ratio; messages per robot per step; the least coverage reached; wall seconds.
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from swarmshape.errors import InputError
from swarmshape.experiments.results import read_rows

KEY = ("shape", "agents", "strategy")
"""What names a row of the table, first; any other ``config.`` value the runs vary follows."""

SAME = {f"config.{name}" for name in ("seed", "strategy", "shape", "agents", "cells", "max_steps")}
"""Settings never shown as columns: the key's, the seed (runs of a row), and the step limit."""

HEADER = (
    "| shape | robots | strategy | formed | steps | steps / bound | distance ratio "
    "| messages / robot / step | least coverage | wall s |"
)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, nargs="*")
    parser.add_argument("--update", type=Path, help="a Markdown file whose tables to remake")
    args = parser.parse_args()
    try:
        if args.update is not None:
            text = BLOCK.sub(_remade, args.update.read_text())
            args.update.write_text(text)
        if args.results:
            print(table(_rows(args.results)))
    except (InputError, OSError) as error:
        print(f"compare.py: error: {error}", file=sys.stderr)
        return 2
    return 0


BLOCK = re.compile(r"(<!-- compare: ([^>]+?) -->\n)(.*?)(<!-- /compare -->)", re.S)
ROOT = Path(__file__).resolve().parent.parent


def _remade(block: re.Match[str]) -> str:
    paths = [ROOT / name for name in block.group(2).split()]
    return block.group(1) + table(_rows(paths)) + "\n" + block.group(4)


def _rows(paths: list[Path]) -> list[dict[str, str]]:
    rows = [row for path in paths for row in read_rows(path)]
    if not rows:
        raise InputError(f"{', '.join(map(str, paths))}: no runs in them yet")
    return rows


def table(rows: list[dict[str, str]]) -> str:
    """The Markdown table of `rows` (sweep results), in order of shape, robots, strategy."""
    names = dict.fromkeys(name for row in rows for name in row if name.startswith("config."))
    varied = [
        name for name in names
        if name not in SAME and len({row.get(name, "") for row in rows}) > 1
    ]  # fmt: skip
    settings = defaultdict(list)
    for row in rows:
        key = (row["shape"], int(row["agents"]), row["strategy"])
        settings[key + tuple(row.get(name) or "-" for name in varied)].append(row)
    extra = [name.removeprefix("config.") for name in varied]
    header = HEADER.replace("| formed", "".join(f"| {name} " for name in extra) + "| formed")
    lines = [header, "|" + " --- |" * header.count(" | ") + " --- |"]
    for setting, runs in sorted(settings.items()):
        formed = [row for row in runs if row["steps"] != ""]
        cells = [setting[0], f"{setting[1]:,}", f"`{setting[2]}`", *setting[3:]]
        cells.append(f"{len(formed)}/{len(runs)}")
        cells.append(_spread([float(row["steps"]) for row in formed], "{:,.0f}"))
        cells.append(_spread([float(row["makespan_ratio"]) for row in formed], "{:.1f}"))
        cells.append(_spread([float(row["distance_ratio"]) for row in formed], "{:.2f}"))
        sent = [
            float(row["messages"]) / (int(row["agents"]) * max(1, int(row["steps_run"])))
            for row in runs
        ]
        cells.append(_spread(sent, "{:.2f}"))
        cells.append(f"{min(float(row['coverage']) for row in runs):.3f}")
        cells.append(_spread([float(row["wall_time"]) for row in runs], "{:,.0f}"))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _spread(values: list[float], form: str) -> str:
    """The median and range of `values`: ``m (lo to hi)``, one value alone, or a dash."""
    if not values:
        return "-"
    low, high, middle = min(values), max(values), statistics.median(values)
    if low == high:
        return form.format(middle)
    return f"{form.format(middle)} ({form.format(low)} to {form.format(high)})"


if __name__ == "__main__":
    sys.exit(main())

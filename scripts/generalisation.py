"""How the benchmark's policies hold up as the swarm grows, with time measured against each
swarm's own makespan lower bound, and write the table into docs/benchmark.md.

    .venv/bin/python scripts/generalisation.py [--policies random,local-swap,learned]
    .venv/bin/python scripts/generalisation.py --check  (exit 1 if the table is out of date)

It keeps its figures in docs/benchmark/generalisation.json (a run adds or replaces the rows
of the policies it measures) and writes the table into docs/benchmark.md.

The leaderboard's star tasks give 100 and 1,000 robots about thirty and twenty times their
makespan bound, but 10,000 robots only seven (2,000 steps over a bound of 293), so their
coverage at the end mixes how well a policy scales with how long it may run. This script
compares them at the same multiple of the bound: the one the 10,000-robot task allows. At
10,000 robots that is the leaderboard's own figure, read from docs/benchmark/NAME.json; at
100 and 1,000 robots every episode of the leaderboard's seeds is run again and stopped at
that multiple of its own bound (the bounds are the task's and seed's, saved in the same
files). About ten minutes of one core for local-swap, less for the others.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from leaderboard import PAGES, RESULTS, fill, names
from swarmshape.env.benchmark import TASKS, policy
from swarmshape.env.benchmark.score import environment, play
from swarmshape.io.files import write_text

SIZES = ("star-100", "star-1k", "star-10k")
LARGEST = SIZES[-1]
FIGURES = RESULTS / "generalisation.json"
"""Each policy's coverages at the multiple, per star task (a run adds or replaces its rows)."""


def coverage_at(name: str, task: str, multiple: float, saved: dict) -> list[float]:
    """Coverage of every saved episode of `task`, run again up to `multiple` bounds."""
    chosen = policy(name)
    env = environment(chosen, TASKS[task])
    covered = []
    for run in saved["tasks"][task]["episodes"]:
        limit = math.floor(multiple * run["makespan_lower_bound"])
        for step, formed in enumerate(play(chosen, TASKS[task], run["seed"], env), 1):
            if formed or step >= limit:
                break
        covered.append(round(env.coverage(), 6))
    env.close()
    return covered


def results(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text(encoding="utf-8"))


def measure(name: str, multiple: float) -> dict[str, list[float]]:
    """Per star task, the coverage of each of the policy's saved episodes at `multiple`."""
    saved = results(name)
    measured = {}
    for task in SIZES[:-1]:
        started = time.perf_counter()
        measured[task] = coverage_at(name, task, multiple, saved)
        print(f"{name} {task}: {time.perf_counter() - started:.0f} s", file=sys.stderr)
    measured[LARGEST] = [run["coverage"] for run in saved["tasks"][LARGEST]["episodes"]]
    return measured


def table(figures: dict) -> str:
    rows = [
        f"Coverage after {figures['multiple']:.2f} times each episode's makespan bound (mean "
        "over seeds, and the least):",
        "",
        "| policy | " + " | ".join(f"{task} ({TASKS[task].robots:,})" for task in SIZES) + " |",
        "| --- |" + " ---: |" * len(SIZES),
    ]
    measured = figures["policies"]
    ranked = [name for name in names() if name in measured]
    ranked += sorted(set(measured) - set(ranked))
    for name in ranked:
        cells = [f"{sum(c) / len(c):.1%} ({min(c):.1%})" for c in measured[name].values()]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(rows) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policies", default="random,local-swap,learned")
    parser.add_argument(
        "--check", action="store_true", help="run nothing: exit 1 if the page's table is stale"
    )
    args = parser.parse_args()
    bound = results("random")["tasks"][LARGEST]["episodes"][0]["makespan_lower_bound"]
    figures = {"multiple": TASKS[LARGEST].steps / bound, "policies": {}}
    if FIGURES.exists():
        figures["policies"] = json.loads(FIGURES.read_text(encoding="utf-8"))["policies"]
    page, text = PAGES[0], PAGES[0].read_text(encoding="utf-8")
    if args.check:
        current = fill(text, {"generalisation": table(figures)}) == text
        print(f"{page.name}: {'current' if current else 'out of date'}")
        return 0 if current else 1
    for name in args.policies.split(","):
        figures["policies"][name] = measure(name, figures["multiple"])
    write_text(FIGURES, json.dumps(figures, indent=2) + "\n")
    made = table(figures)
    print(made, end="")
    write_text(page, fill(text, {"generalisation": made}))
    return 0


if __name__ == "__main__":
    sys.exit(main())

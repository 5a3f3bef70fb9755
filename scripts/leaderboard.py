"""Write the benchmark's tables into docs/benchmark.md and the README, and its figure
docs/benchmark/coverage.png, from the results in docs/benchmark/ (made by
``swarmshape benchmark NAME --json docs/benchmark/NAME.json``).

    .venv/bin/python scripts/leaderboard.py          (rewrites the tables and the figure)
    .venv/bin/python scripts/leaderboard.py --check  (exit 1 if a table is out of date)

The rows, in order: random, every built-in local program, the learned policy. The figure
(the plot extra) shows every episode's coverage at the end, task by task, with each policy's
mean as a bar: the tasks at 100, 1,000 and 10,000 robots side by side show how each policy
holds up as the swarm grows.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from swarmshape.env.benchmark import leaderboard, local_programs, to_markdown
from swarmshape.env.benchmark.suite import table
from swarmshape.io.files import atomic_write, write_text

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "docs" / "benchmark"
PAGES = (ROOT / "docs" / "benchmark.md", ROOT / "README.md")
FIGURE = RESULTS / "coverage.png"


def names() -> list[str]:
    """The leaderboard's rows, in order."""
    return ["random", *local_programs(), "learned"]


def rows() -> list[dict]:
    return [json.loads((RESULTS / f"{name}.json").read_text()) for name in names()]


def tables() -> dict[str, str]:
    """Each marked table's name and its content now."""
    results = rows()
    details = "\n".join(to_markdown(row) for row in results)
    return {"suite": table(), "leaderboard": leaderboard(results), "details": details}


def fill(page: str, made: dict[str, str]) -> str:
    """`page` with the tables named in `made` (name: content) put between their markers."""
    for name, content in made.items():
        pattern = re.compile(rf"(<!-- {name}: [^>]*-->\n).*?(<!-- /{name} -->)", re.S)
        page = pattern.sub(lambda match, c=content: match[1] + c + match[2], page)
    return page


def draw(results: list[dict], path: Path) -> None:
    """Coverage at the end per task (bars: means; dots: episodes), one colour per policy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(results[0]["tasks"])
    width = 0.8 / len(results)
    figure, axes = plt.subplots(figsize=(11, 4.2), layout="constrained")
    for index, row in enumerate(results):
        where = [task + (index - (len(results) - 1) / 2) * width for task in range(len(names))]
        means = [row["tasks"][name]["coverage"] for name in names]
        bars = axes.bar(where, means, width * 0.9, label=row["policy"], alpha=0.75)
        for x, name in zip(where, names, strict=True):
            dots = [episode["coverage"] for episode in row["tasks"][name]["episodes"]]
            axes.plot([x] * len(dots), dots, ".", color=bars.patches[0].get_facecolor(),
                      markeredgecolor="black", markeredgewidth=0.4, markersize=4)  # fmt: skip
    axes.set_xticks(range(len(names)), names, rotation=20)
    axes.set_ylabel("coverage at the end of the episode")
    axes.set_ylim(0, 1.02)
    axes.yaxis.set_major_formatter(matplotlib.ticker.PercentFormatter(1.0))
    axes.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    axes.set_title(f"{results[0]['suite']}: bars are means, dots single episodes")
    atomic_write(path, lambda tmp: figure.savefig(tmp, format="png", dpi=110))
    plt.close(figure)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only say whether they are current")
    args = parser.parse_args()
    stale, made = [], tables()
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        if fill(text, made) != text:
            stale.append(page)
            if not args.check:
                write_text(page, fill(text, made))
    for page in stale:
        print(f"{page.relative_to(ROOT)}: {'out of date' if args.check else 'rewritten'}")
    if not args.check:
        draw(rows(), FIGURE)
        print(f"{FIGURE.relative_to(ROOT)}: drawn")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())

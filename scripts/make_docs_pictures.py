"""Make the pictures in docs/ again, from the code as it is now, so that none goes stale.

    .venv/bin/python scripts/make_docs_pictures.py                 # every picture
    .venv/bin/python scripts/make_docs_pictures.py editor.png star.gif --out /tmp/pictures
    .venv/bin/python scripts/make_docs_pictures.py --list

Windows are drawn offscreen. coverage.png and steps.png need the plot extra and run the sweep
sweeps/strategies.toml first (36 runs, a few minutes on two cores; `--results CSV` plots a
sweep's results already there); mean-shift-coverage.png and mean-shift-steps.png plot
sweeps/mean-shift-fig4.csv, running what it lacks first. fault-coverage.png and
faults-healing.png form and heal a 1,000-cell disc under each strategy (`scripts/faults.py`;
the paper's method takes the most).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

import pygame

import faults
import screenshot
from swarmshape.cli import main as swarmshape
from swarmshape.config import configure
from swarmshape.core.world import blank_world
from swarmshape.io.scenario import PALETTE, parse_colour
from swarmshape.runs import start_swarm
from swarmshape.session import BLANK_ARENA, BLANK_POSE
from swarmshape.ui.viewer import Viewer

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"


def window(shape: str, **options) -> Callable[[Path, argparse.Namespace], None]:
    """A screenshot of a run in the window (see `screenshot.shoot`), saved as the picture."""
    return lambda out, _: print(f"step {screenshot.shoot(ROOT / shape, out, **options)}")


def editor(out: Path, _: argparse.Namespace) -> None:
    """The editor on a new drawing: an L painted with a 3-cell brush, the help panel open."""
    world = blank_world(BLANK_ARENA, BLANK_POSE, "drawn.png", parse_colour(PALETTE[0]))
    with tempfile.TemporaryDirectory() as folder:
        view = Viewer(
            lambda painted: start_swarm(configure(), painted),
            world,
            title="drawn.png",
            start=False,
            shape_file=Path(folder) / "drawn.png",
            fps=0,
        )

        def post(kind: int, **attributes) -> None:
            pygame.event.post(pygame.event.Event(kind, **attributes))

        def at(cell: tuple[int, int]) -> tuple[int, int]:
            return view.renderer.cell_rect(cell, view._world_area()).center

        for _ in range(2):
            post(pygame.KEYDOWN, key=pygame.K_RIGHTBRACKET, mod=0, unicode="]")
        for start, end in (((36, 12), (17, 12)), ((17, 12), (17, 24))):
            post(pygame.MOUSEBUTTONDOWN, pos=at(start), button=1)
            post(pygame.MOUSEMOTION, pos=at(end), rel=(0, 0), buttons=(1, 0, 0))
            post(pygame.MOUSEBUTTONUP, pos=at(end), button=1)
        post(pygame.KEYDOWN, key=pygame.K_h, mod=0, unicode="h")
        view.tick()
        pygame.image.save(view.screen, out)
        pygame.quit()


def recording(out: Path, _: argparse.Namespace) -> None:
    """The star forming under `optimal`, every third step, as the README's command makes it."""
    command = [str(ROOT / "shapes/star.png"), "--headless", "--seed", "1"]
    if swarmshape([*command, "--record", str(out), "--record-every", "3", "--force"]):
        raise SystemExit(f"{out.name}: the recording failed")


def plots(out: Path, args: argparse.Namespace) -> None:
    """coverage.png and steps.png beside each other, from the shipped sweep's results."""
    with tempfile.TemporaryDirectory() as folder:
        results = args.results or Path(folder) / "strategies.csv"
        if args.results is None:
            sweep = ["sweep", str(ROOT / "sweeps/strategies.toml"), "--out", str(results)]
            if swarmshape(sweep):
                raise SystemExit("the sweep behind the plots failed")
        if swarmshape(["plot", str(results), "--out", str(out.parent), "--force"]):
            raise SystemExit("the plots failed")


def comparison_plots(out: Path, _: argparse.Namespace) -> None:
    """mean-shift-coverage.png and mean-shift-steps.png: Sun et al.'s Fig. 4 in spirit, from
    the shipped sweep's results (the sweep runs the runs its CSV lacks first)."""
    sweep = ROOT / "sweeps/mean-shift-fig4.toml"
    if swarmshape(["sweep", str(sweep)]):
        raise SystemExit("the sweep behind the comparison failed")
    with tempfile.TemporaryDirectory() as folder:
        if swarmshape(["plot", str(sweep.with_suffix(".csv")), "--out", folder, "--force"]):
            raise SystemExit("the comparison plots failed")
        for name in ("coverage.png", "steps.png"):
            (Path(folder) / name).replace(out.parent / f"mean-shift-{name}")


def fault_pictures(out: Path, _: argparse.Namespace) -> None:
    faults.pictures(["optimal", "greedy", "random", "paper"], 1000, out.parent)


PICTURES: dict[tuple[str, ...], Callable[[Path, argparse.Namespace], None]] = {
    ("star-concurrent.png",): window("shapes/star.png", steps=60),
    ("horseshoe.png",): window("shapes/horseshoe.png", strategy="paper", steps=1800),
    ("self-assembly.png",): window(
        "shapes/letter-k.png",
        cells=20,
        strategy="self-assembly",
        start="packed",
        steps=1500,
        overlays=("values",),
    ),
    ("local-overlays.png",): window(
        "shapes/square.png",
        cells=12,
        strategy=f"{ROOT / 'examples/my_program.py'}:Gather",
        steps=60,
        size=(960, 600),
        overlays=("values", "links"),
    ),
    ("mean-shift.png",): window(
        "shapes/letter-k.png", cells=24, strategy="mean-shift", steps=150, overlays=("values",)
    ),
    ("local-swap.png",): window("shapes/letter-k.png", cells=24, strategy="local-swap", steps=300),
    ("mean-shift-10k.png",): window(  # three minutes: 9,946 robots, 3,000 steps
        "shapes/letter-s.png", cells=142, strategy="mean-shift", steps=3000
    ),
    ("editor.png",): editor,
    ("star.gif",): recording,
    ("coverage.png", "steps.png"): plots,
    ("mean-shift-coverage.png", "mean-shift-steps.png"): comparison_plots,
    ("fault-coverage.png", "faults-healing.png"): fault_pictures,
}
"""Who makes each picture; one maker may make several."""


def main() -> None:
    names = [name for made in PICTURES for name in made]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help=f"of {', '.join(names)}")
    parser.add_argument("--out", type=Path, default=DOCS, help="folder (default docs/)")
    parser.add_argument("--results", type=Path, help="a sweep's CSV to plot instead of sweeping")
    parser.add_argument("--list", action="store_true", help="name the pictures and stop")
    args = parser.parse_args()
    if args.list:
        print("\n".join(names))
        return
    unknown = sorted(set(args.names) - set(names))
    if unknown:
        parser.error(f"no picture {unknown[0]!r}; choose from {', '.join(names)}")
    args.out.mkdir(parents=True, exist_ok=True)
    for made, make in PICTURES.items():
        if args.names and not set(made) & set(args.names):
            continue
        started = time.perf_counter()
        make(args.out / made[0], args)
        print(f"{', '.join(made)}: {time.perf_counter() - started:.0f} s", flush=True)


if __name__ == "__main__":
    main()

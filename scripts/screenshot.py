"""Save what the window shows after some steps, without a screen (for docs and for looking).

python scripts/screenshot.py shapes/horseshoe.png --steps 1600 --out docs/horseshoe.png
python scripts/screenshot.py shapes/square.png --cells 12 --strategy examples/my_program.py:Gather \
    --steps 60 --size 960 600 --overlay values --overlay links --out docs/local-overlays.png
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import pygame

from swarmshape.config import configure
from swarmshape.errors import InputError
from swarmshape.runs import load_world, start_cells, start_swarm
from swarmshape.ui.render import OVERLAYS
from swarmshape.ui.viewer import Viewer


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("path", type=Path)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--size", type=int, nargs=2, default=(1280, 800))
    parser.add_argument("--strategy", default="optimal")
    parser.add_argument("--start", help="packed, scatter or a CSV (as the run's --start)")
    parser.add_argument("--cells", type=int, help="cells across the shape's long side")
    parser.add_argument(
        "--overlay", action="append", default=[], choices=OVERLAYS, help="a local program's"
    )
    args = parser.parse_args()
    options = vars(args)
    path, out = options.pop("path"), options.pop("out")
    options["size"], options["overlays"] = tuple(args.size), options.pop("overlay")
    try:
        step = shoot(path, out, **options)
    except InputError as error:  # a bad shape or scenario: one line, as the command line says it
        print(f"screenshot.py: {error}", file=sys.stderr)
        return 2
    print(f"{out}: step {step}")
    return 0


def shoot(
    path: Path,
    out: Path,
    *,
    steps: int = 1000,
    seed: int = 1,
    size: tuple[int, int] = (1280, 800),
    strategy: str = "optimal",
    start: str | None = None,
    cells: int | None = None,
    overlays: tuple[str, ...] = (),
) -> int:
    """Run `path` for `steps` steps in an offscreen window, paused, with `overlays` on, and
    save the window to `out`; return the step shown."""
    config = configure(path, seed=seed, strategy=strategy, start=start, cells=cells)
    world = load_world(config)
    first = start_cells(config, world)
    viewer = Viewer(
        lambda new: start_swarm(config, new, first if new is world else None),
        world,
        title=world.name,
        size=size,
        speed=1,
        fps=0,
    )
    while viewer.swarm.step_count < steps:
        viewer.step()
    viewer.paused = True
    viewer.overlays = set(overlays)
    viewer.tick()
    pygame.image.save(viewer.screen, out)
    step = viewer.swarm.step_count
    pygame.quit()
    return step


if __name__ == "__main__":
    sys.exit(main())

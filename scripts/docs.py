"""Build the API reference from the docstrings, with pdoc (in the test extra):

    .venv/bin/python scripts/docs.py [DIR]

into DIR (default docs/api/, which git ignores: the reference is made, never committed); open
DIR/index.html. It covers the package's public names (`swarmshape`: every run setting in
`RunConfig`, the plug-in bases `Strategy` and `Program` with every hook, `Perception`,
`Blueprint`), how a plug-in declares its own options (`swarmshape.core.options`), and the
learning environment with its benchmark. Any warning while building fails it (exit 1), so a
broken docstring or reference is found here, not by a reader.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import pdoc
import pdoc.render

ROOT = Path(__file__).resolve().parent.parent
MODULES = ("swarmshape", "swarmshape.core.options", "swarmshape.env", "swarmshape.env.benchmark")


def build(out: Path) -> list[str]:
    """Write the reference into `out`; return the warnings raised while building it."""
    pdoc.render.configure(docformat="restructuredtext", show_source=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(*MODULES, output_directory=out)
    return [f"{w.category.__name__}: {w.message}" for w in caught]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", type=Path, default=ROOT / "docs" / "api")
    args = parser.parse_args()
    problems = build(args.out)
    for problem in problems:
        print(f"docs: {problem}", file=sys.stderr)
    if problems:
        return 1
    print(f"docs: the API reference is in {args.out / 'index.html'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

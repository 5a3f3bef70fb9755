"""Every script in examples/ runs as a user would run it, and says what it promises."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from tests.conftest import python

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
PROMISES = {
    "headless.py": "robots formed it in",
    "my_strategy.py": "no problems found",
    "frames.py": "frames of shape (200, 320, 3) and dtype uint8",
    "my_program.py": "cells from a seed",
    "learn_random.py": "a frame of shape (400, 640, 3)",
    "learn_scripted.py": "shape formed: True, coverage 100%",
    "learn_cem.py": "coverage with the trained policy: 33% (from 0%)",
    "learn_benchmark.py": "weights in learned.json",
}
README = (EXAMPLES.parent / "README.md").read_text()
SCRIPTED = re.search(
    r"learn_scripted.py`.*?\((\d+)\s+robots, (\d+) steps, coverage (\d+%)\)", README, re.S
)
CEM = re.search(r"learn_cem.py`.*?from (\d+%) to (\d+%) .*?, and (.*?) on three\s", README, re.S)
README_FIGURES = {
    "learn_scripted.py": [
        "{} robots, {} steps".format(*SCRIPTED.groups()),
        f"coverage {SCRIPTED.group(3)}",
    ],
    "learn_cem.py": [
        "coverage with the trained policy: {1} (from {0})".format(*CEM.groups()),
        f"on three new episodes: {CEM.group(3)}",
    ],
}
"""What the README says these examples print: the figures checked against their output."""
ARGUMENTS = {"learn_benchmark.py": ["--tiny"]}
"""What an example needs to finish in seconds (the full training takes most of an hour)."""


def test_every_example_is_listed_here():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(PROMISES)


@pytest.mark.parametrize("name", sorted(PROMISES))
def test_the_example_runs(name, tmp_path):
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    result = python(str(EXAMPLES / name), *ARGUMENTS.get(name, []), cwd=tmp_path, env=env)
    assert result.returncode == 0, result.stderr
    for promise in [PROMISES[name], *README_FIGURES.get(name, [])]:
        assert promise in result.stdout


def test_the_library_page_runs_as_written(monkeypatch):
    """docs/library.md's code blocks, in order, in one namespace, from the repository root."""
    page = (EXAMPLES.parent / "docs" / "library.md").read_text()
    blocks = [part.split("```", 1)[0] for part in page.split("```python\n")[1:]]
    monkeypatch.chdir(EXAMPLES.parent)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "docs/library.md", "exec"), namespace)
    assert namespace["metrics"]["coverage"] == 1.0
    assert namespace["rgb"].shape == (400, 640, 3)
    assert namespace["runner"].observers[0].counts[-1] > 0

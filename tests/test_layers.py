"""The layers import downward only: the core is numpy, scipy and numba (its compiled kernels),
and nothing below the window loads pygame. Read from the source, so a stray import fails here
before anyone notices."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import swarmshape

PACKAGE = Path(swarmshape.__file__).parent
STDLIB = sys.stdlib_module_names

ALLOWED = {
    "core": {"numpy", "numba", "scipy", "swarmshape.core", "swarmshape.errors"},
    "strategies": {"numpy", "scipy", "swarmshape.core", "swarmshape.errors",
                   "swarmshape.strategies"},
    "io": {"numpy", "PIL", "swarmshape.core", "swarmshape.errors", "swarmshape.io"},
    "ui": {"numpy", "scipy", "pygame", "PIL", "imageio_ffmpeg", "swarmshape.core",
           "swarmshape.errors", "swarmshape.io", "swarmshape.ui", "swarmshape.runs",
           "swarmshape.config"},
    "experiments": {"numpy", "matplotlib", "dask", "swarmshape.core", "swarmshape.errors",
                    "swarmshape.io", "swarmshape.experiments", "swarmshape.runs",
                    "swarmshape.config"},
    # the learning environment draws through ui/screen.py, loaded only to render
    # the benchmark drives the built-in local programs as policies, by name; its learned
    # policy reads the shape as a distance field (scipy.ndimage)
    "env": {"numpy", "scipy", "gymnasium", "pettingzoo", "swarmshape.core",
            "swarmshape.errors", "swarmshape.io", "swarmshape.env", "swarmshape.runs",
            "swarmshape.config", "swarmshape.strategies", "swarmshape.ui.screen"},
}  # fmt: skip


def imports(path: Path) -> set[str]:
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            found.add(node.module)
    return found


def allowed(name: str, layer: str) -> bool:
    top = name.split(".")[0]
    return top in STDLIB or any(name == ok or name.startswith(ok + ".") for ok in ALLOWED[layer])


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_each_layer_imports_only_what_sits_below_it(layer):
    wrong = [
        f"{path.relative_to(PACKAGE)} imports {name}"
        for path in sorted((PACKAGE / layer).rglob("*.py"))
        for name in sorted(imports(path))
        if not allowed(name, layer)
    ]
    assert wrong == []


def test_a_headless_formation_from_code_never_loads_pygame():
    code = (
        "import sys\n"
        "import numpy as np\n"
        "from swarmshape.core.shape import Shape\n"
        "from swarmshape.core.swarm import Swarm\n"
        "from swarmshape.core.world import GroupSpec, build_world\n"
        "from swarmshape.strategies import create\n"
        "world = build_world([GroupSpec('g', Shape(np.ones((4, 5), bool)), (1, 2, 3))])\n"
        "swarm = Swarm(world, create('optimal'), 1)\n"
        "while not swarm.complete:\n"
        "    swarm.step()\n"
        "print(sorted(m for m in ('pygame', 'PIL', 'matplotlib') if m in sys.modules))\n"
    )
    assert loaded_by(code) == "[]"


def test_the_command_line_starts_without_numba_or_scipys_submodules():
    """Numba and scipy's submodules load at their first use (docs/architecture.md): together
    they were 0.35 s of the 0.6 s that every command, even `--help`, took to start."""
    code = (
        "import sys\n"
        "import swarmshape.cli\n"
        "heavy = ('numba', 'scipy.ndimage', 'scipy.sparse', 'pygame', 'matplotlib')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
    )
    assert loaded_by(code) == "[]"


def loaded_by(code: str) -> str:
    """What `code`, run in a fresh interpreter, prints."""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_the_learning_environment_steps_without_loading_pygame():
    code = (
        "import sys\n"
        "import numpy as np\n"
        "import swarmshape.env\n"
        "vec = swarmshape.env.vector_env(np.ones((2, 3), bool), max_steps=5)\n"
        "vec.reset(seed=1)\n"
        "vec.step(np.zeros(vec.num_envs, dtype=np.int64))\n"
        "print(sorted(m for m in ('pygame', 'matplotlib') if m in sys.modules))\n"
    )
    assert loaded_by(code) == "[]"


def test_the_public_names_are_where_the_package_says():
    homes = [name for names in swarmshape._HOMES.values() for name in names]
    assert sorted(homes) == sorted(swarmshape.__all__)
    for name in swarmshape.__all__:
        assert getattr(swarmshape, name) is not None

"""Shared fixtures. Tests never need a screen: SDL uses its dummy drivers."""

from __future__ import annotations

import importlib.util
import json
import os
import select
import signal
import subprocess
import sys
import tempfile

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from collections.abc import Iterable, Sequence
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from hypothesis import settings
from scipy import ndimage

from swarmshape.core.shape import Shape
from swarmshape.core.swarm import Swarm
from swarmshape.core.world import GroupSpec, World, build_world
from swarmshape.strategies import create

SHAPES = Path(__file__).resolve().parent.parent / "shapes"

# The suite's own pace: enough examples of each property to catch a rule broken anywhere common,
# in the few minutes a change's test run may take. `--slow` runs twenty times as many, the
# tests marked slow (large swarms, long regressions) and every case of the matrices that
# `each_choice` thins out: what a night run is for. `scripts/test` (and so CI) checks the same
# examples every run ("ci"), so a change is judged on what it changed and a red build always
# reproduces; plain `pytest` draws new ones and so keeps exploring.
settings.register_profile("quick", max_examples=50)
settings.register_profile("ci", parent=settings.get_profile("quick"), derandomize=True,
                          print_blob=True)  # fmt: skip
settings.register_profile("slow", max_examples=1000)
settings.load_profile(os.environ.get("SWARMSHAPE_HYPOTHESIS_PROFILE", "quick"))
WHOLE_RUN_EXAMPLES = 10
"""Examples by default of a property each of whose examples is a whole run or two (in all, over
its parametrised cases): `--slow` gives it the profile's thousand."""
_slow = False


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--slow", action="store_true", help="the slow tests too, and many more examples"
    )
    parser.addoption(
        "--shard",
        default="0/1",
        metavar="K/N",
        help="only every Nth test, from the Kth (scripts/test runs N of these side by side)",
    )


def pytest_configure(config: pytest.Config) -> None:
    global _slow
    config.addinivalue_line("markers", "slow: runs only with --slow (large swarms, long runs)")
    # A shell without job control starts a command put in the background (scripts/test's
    # shards but the first, where no `timeout` resets it) with Ctrl+C ignored, and so every
    # run a test starts: the tests of Ctrl+C then failed. Taken back, as at an interactive
    # prompt.
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    _slow = config.getoption("--slow")
    if _slow:
        settings.load_profile("slow")


def pytest_unconfigure(config: pytest.Config) -> None:
    _CommandServer.stop()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Leave the tests marked slow out of a run without `--slow`, and in a shard of the suite
    the other shards' tests; say so."""
    if not config.getoption("--slow"):
        _keep(config, items, [not item.get_closest_marker("slow") for item in items])
    shard, shards = (int(part) for part in config.getoption("--shard").split("/"))
    _keep(config, items, [index % shards == shard for index in range(len(items))])


def _keep(config: pytest.Config, items: list[pytest.Item], kept: list[bool]) -> None:
    """Keep the `items` marked in `kept`; the others are deselected."""
    if not all(kept):
        pairs = list(zip(items, kept, strict=True))
        config.hook.pytest_deselected(items=[item for item, keep in pairs if not keep])
        items[:] = [item for item, keep in pairs if keep]


def slow_for(slow: str, param: str) -> object:
    """`param` of a parametrised test, marked slow when it is `slow` (a plug-in whose runs of
    the test take a minute where the others take seconds)."""
    return pytest.param(param, marks=pytest.mark.slow) if param == slow else param


def whole_runs(cases: int = 1) -> int:
    """`max_examples` for each of the `cases` of a property whose examples are whole runs: its
    share of `WHOLE_RUN_EXAMPLES` (of the profile's examples with `--slow`), at least one."""
    return max(1, (settings().max_examples if _slow else WHOLE_RUN_EXAMPLES) // cases)


def each_choice(
    cases: Iterable[Sequence[object]], keep: Iterable[Sequence[object]] = ()
) -> list[object]:
    """The `cases` of a parametrised test (one value per argument each), those beyond a few
    marked slow: the default run keeps the cases in `keep` (a regression under the strategy
    it broke, say) and a handful more in which every value of every argument appears at least
    once (each-choice coverage, chosen greedily and so the same every run, which pairs the
    arguments' values off much as a diagonal would); `--slow` runs them all."""
    cases = [tuple(case) for case in cases]
    kept = {cases.index(tuple(case)) for case in keep}
    covered = {choice for index in kept for choice in enumerate(cases[index])}
    while True:
        new = [len(set(enumerate(case)) - covered) for case in cases]
        best = max(range(len(cases)), key=new.__getitem__)
        if new[best] == 0:
            break
        kept.add(best)
        covered |= set(enumerate(cases[best]))
    return [
        pytest.param(*case, marks=() if index in kept else pytest.mark.slow)
        for index, case in enumerate(cases)
    ]


@pytest.fixture
def shapes() -> Path:
    return SHAPES


def grid_from(text: str) -> np.ndarray:
    """A grid from rows of '#' (ink) and '.' (empty)."""
    return np.array([[c == "#" for c in row] for row in text.split()], dtype=bool)


def dilated(blocked: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """The fewest moves between side neighbours from `sources` to each cell of one square,
    round its `blocked` cells (-1: none; a source may be blocked), a scipy dilation a level:
    the plain way that local programs' compiled breadth-first passes must agree with."""
    sides = ndimage.generate_binary_structure(2, 1)
    steps = np.where(sources, 0, -1)
    front, reached, level = sources, sources, 0
    while front.any():
        level += 1
        front = ndimage.binary_dilation(front, sides) & ~blocked & ~reached
        steps[front] = level
        reached = reached | front
    return steps


def world_of(shape: np.ndarray | Shape, agents: int | None = None) -> World:
    shape = shape if isinstance(shape, Shape) else Shape(shape)
    return build_world([GroupSpec("test", shape, (200, 60, 60), agents)])


def make_swarm(
    shape: np.ndarray | Shape,
    *,
    agents: int | None = None,
    seed: int = 0,
    strategy: str = "paper",
) -> Swarm:
    """A swarm forming `shape` (moved beside its seeds for a program that grows from them,
    as `runs.load_world` does)."""
    program = create(strategy)
    shape = shape if isinstance(shape, Shape) else Shape(shape)
    if getattr(program, "grows_from_seeds", False):
        shape = shape.seeded()
    return Swarm(world_of(shape, agents), program, seed)


def script(name: str) -> ModuleType:
    """A script of scripts/ as a module (they are not a package)."""
    spec = importlib.util.spec_from_file_location(name, SHAPES.parent / "scripts" / f"{name}.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # a dataclass looks its module up there
    spec.loader.exec_module(module)
    return module


class _CommandServer:
    """A process that has imported swarmshape and loaded its compiled kernels, and forks a
    child for each command line (`tests/command_server.py`); started at the first call."""

    process: subprocess.Popen | None = None
    SLACK = 60
    """Seconds the server may take beyond a command's timeout (its own start-up, say)."""

    @classmethod
    def run(cls, request: dict, timeout: float) -> int | None:
        """The command's exit code, or None if it ran past `timeout` (and was killed)."""
        if cls.process is None or cls.process.poll() is not None:
            server = Path(__file__).with_name("command_server.py")
            cls.process = subprocess.Popen(
                [sys.executable, str(server)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                text=True,
            )  # fmt: skip
        assert cls.process.stdin and cls.process.stdout
        try:
            cls.process.stdin.write(json.dumps({**request, "timeout": timeout}) + "\n")
            cls.process.stdin.flush()
            if not select.select([cls.process.stdout], [], [], timeout + cls.SLACK)[0]:
                raise RuntimeError("the command server does not answer")
            answer = json.loads(cls.process.stdout.readline() or "null")
            if answer is None:
                raise RuntimeError("the command server ended")
        except BaseException:  # a request half made leaves the server out of step: a new one
            cls.process.kill()
            cls.stop()
            raise
        return None if answer["timed_out"] else answer["code"]

    @classmethod
    def stop(cls) -> None:
        if cls.process is not None:
            cls.process.communicate()  # its input ends, and so does it
            cls.process = None


FRESH_ONLY = {"PYTHONHASHSEED", "PYTHONWARNINGS", "PYTHONIOENCODING", "PYTHONINTMAXSTRDIGITS",
              "PYTHONUTF8", "PYTHONDEVMODE", "PYTHONSAFEPATH"}  # fmt: skip
"""Start-up settings of the environment that only a fresh interpreter reads."""


def python(
    *args: str,
    cwd: Path | str | None = None,
    env: dict | None = None,
    timeout: float = 120,
    fresh: bool = False,
) -> subprocess.CompletedProcess:
    """What ``subprocess.run([sys.executable, *args], capture_output=True, text=True)`` gives,
    for ``-m MODULE ...`` or ``SCRIPT ...``: a process of its own (its exit code, a crash
    its own), but forked from one that has imported swarmshape already, so the suite's
    150-odd command lines skip the 0.3 s each that a fresh interpreter takes to start. A
    `fresh` interpreter where the test needs one: forked children share one hash seed, so two
    runs compared for determinism each get their own."""
    env = dict(os.environ if env is None else env)
    cwd = os.path.abspath(cwd or os.getcwd())
    starts_fresh = {name for name in FRESH_ONLY if env.get(name) != os.environ.get(name)}
    if fresh or starts_fresh or not hasattr(os, "pidfd_open"):
        command = [sys.executable, *args]
        return subprocess.run(
            command, capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout
        )
    with tempfile.TemporaryDirectory() as folder:
        out, err = Path(folder) / "out", Path(folder) / "err"
        request = {"args": list(args), "cwd": cwd, "env": env, "out": str(out), "err": str(err)}
        code = _CommandServer.run(request, timeout)
        stdout, stderr = out.read_text(errors="replace"), err.read_text(errors="replace")
    if code is None:
        raise subprocess.TimeoutExpired([sys.executable, *args], timeout, stdout, stderr)
    return subprocess.CompletedProcess([sys.executable, *args], code, stdout, stderr)

"""Fuzz cases for the command line and every file it reads, and the rules each outcome keeps.

Shared by ``tests/test_fuzz.py`` (hypothesis, in-process, small by default) and
``scripts/fuzz.py`` (thousands of cases, each in a forked process). A case is drawn through a
`Pick` (hypothesis' data, or a seeded `random.Random`), written into a fresh copy of a folder
of valid inputs (`make_material`), and run there. `problems` says in words what an outcome did
wrong: an exit status other than 0, 2 or 3 (3 only for a headless run or a check), stderr other
than one error line and one warning line, a traceback, or a file changed, added or removed that
the command line did not name as an output (and, after exit 2, any new file at all).
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import fnmatch
import hashlib
import io
import json
import os
import re
import resource
import shlex
import shutil
import signal
import stat
import struct
import sys
import tempfile
import threading
import time
import zipfile
import zlib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np
from PIL import Image

T = TypeVar("T")

COMMANDS = ("run", "edit", "sweep", "plot", "strategies", "check")
FRAME_FILES = "frame-[0-9][0-9][0-9][0-9][0-9][0-9][0-9].png"
TEMP_PREFIX = ".swarmshape-"
PROGRESS = re.compile(r"^swarmshape: (step \d+, coverage .*|\d+/\d+ runs)$")
"""The progress lines a run or a sweep writes off a terminal every 10 s (a slow machine)."""
STOPPED = (128 + signal.SIGTERM, -signal.SIGTERM)
"""How a process sent SIGTERM may end: having cleaned up, or at once (before a run began)."""
OVERLAPS = re.compile(r", ([\d,]+) overlaps?, seed")
"""Where a summary line says how many overlaps the run had: always 0, or something lied."""
TIMEOUT = 120
"""Seconds a case may take before it counts as hung."""
LONG_SWEEP = 1000
"""Runs of a sweep the fuzz waits for (a run of the sweep cases takes 0.05 to 0.2 s)."""


class Pick(Protocol):
    """Where a case's choices come from."""

    def integer(self, low: int, high: int) -> int: ...

    def choice(self, options: Sequence[T]) -> T: ...


# --- the folder of valid inputs every case starts from ------------------------------------------

SHAPE = """
..####.
.#####.
##...##
##...##
#######
#.....#
"""

SCENARIO = """name = "fuzz"
strategy = "optimal"
seed = 3
max_steps = 40
max_speed = 0.5
max_accel = 0.125
arena = [30, 20]

[[groups]]
name = "a"
shape = "shape.png"
agents = 30
colour = "#3a6fd8"
pose = { x = 2, y = 2, rotation = 0 }
cells = 7
threshold = 0.5
invert = false

[[groups]]
name = "b"
shape = "sub/dot.png"
pose = { x = 20, y = 12, rotation = 90 }
"""

SWEEP = """shapes = ["shape.png", "sub/dot.png"]
strategies = ["optimal", "paper"]
agents = 0
seeds = 1
cells = 7
max_steps = 60
curve_every = 5
"""

STRATEGY = """from swarmshape.strategies.concurrent import Optimal


class Mine(Optimal):
    name = "mine"
    description = "the optimal strategy, from a file"
"""

HOSTILE = """import sys
import numpy as np
from swarmshape.strategies.concurrent import Optimal


class Raises(Optimal):
    name = "raises"

    def on_step(self, swarm):
        if swarm.step == 2:
            raise RuntimeError("a bug of the user's")
        super().on_step(swarm)


class Writes(Optimal):
    name = "writes"

    def on_step(self, swarm):
        swarm.world.seeds[:] = 0
        swarm.targets[0] = 3
        swarm.target[:] = 0


class Nobody(Optimal):
    name = "nobody"

    def on_step(self, swarm):
        swarm.assign(np.array([-1, 10**9]), np.array([0, 0]))


class Exits(Optimal):
    name = "exits"

    def on_step(self, swarm):
        sys.exit(swarm.step)


class Plans(Optimal):
    name = "plans"

    def on_start(self, swarm):
        self.order = list(np.argsort(swarm.targets[:, 0]))
        super().on_start(swarm)


class Keeps(Optimal):
    name = "keeps"

    def on_start(self, swarm):
        self.table = {"cells": 1}
        super().on_start(swarm)


class Loops(Optimal):
    name = "loops"

    def on_step(self, swarm):
        while swarm.step == 1:
            pass
        super().on_step(swarm)
"""
"""Strategies whose own code fails every way a user's might (issue 29): each must be one line
naming it (exit 2), or a problem `check` reports (exit 3); `check` stops the loop. And two that
keep state set up in on_start: one a state file holds, one it cannot."""
HOSTILE_CLASSES = ["hostile.py:Raises", "hostile.py:Writes", "hostile.py:Nobody",
                   "hostile.py:Exits", "hostile.py:Plans", "hostile.py:Keeps",
                   "broken.py:X"]  # fmt: skip

INPUTS = {
    "image": ["shape.png", "sub/dot.png"],
    "scenario": ["scenario.toml"],
    "sweep": ["sweep.toml"],
    "start": ["start.csv"],
    "results": ["results.csv"],
    "state": ["paper.state", "optimal.state", "faults.state"],
}
"""The valid inputs of each kind in the material folder."""
OTHERS = ["notes.txt", "data.npz", "mine.py", "sub", "."]


def make_material(folder: Path) -> Path:
    """Write the valid inputs (see `INPUTS`) into `folder`, with swarmshape itself."""
    from swarmshape.config import configure
    from swarmshape.core.faults import FaultEvent
    from swarmshape.experiments.results import open_results
    from swarmshape.experiments.sweep import read_sweep, run_key, run_one
    from swarmshape.runs import build, load_world, run, save

    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sub").mkdir(exist_ok=True)
    grid = np.array([[c == "#" for c in row] for row in SHAPE.split()])
    Image.fromarray(np.where(grid, 0, 255).astype(np.uint8)).save(folder / "shape.png")
    Image.new("L", (1, 1), 0).save(folder / "sub" / "dot.png")
    (folder / "scenario.toml").write_text(SCENARIO)
    (folder / "sweep.toml").write_text(SWEEP)
    (folder / "mine.py").write_text(STRATEGY)
    (folder / "hostile.py").write_text(HOSTILE)
    (folder / "broken.py").write_text("raise ImportError('broken on import')\n")
    (folder / "notes.txt").write_text("a note of the user's, not an input of any kind\n")
    np.savez(folder / "data.npz", values=np.arange(5))
    world = load_world(configure(folder / "shape.png", seed=0))
    cells = world.start_cells()[:: max(1, len(world.start_cells()) // world.agents)]
    rows = "".join(f"{x},{y}\n" for x, y in cells[: world.agents])
    (folder / "start.csv").write_text("x,y\n" + rows)
    for strategy in ("paper", "optimal"):
        config = configure(folder / "shape.png", strategy=strategy, seed=1)
        save(run(build(config), max_steps=6), folder / f"{strategy}.state", config)
    faults = (FaultEvent(2, "remove", 0.2), FaultEvent(3, "stall", 2))  # a log, lost, stalled
    config = configure(folder / "shape.png", strategy="greedy", seed=1, faults=faults)
    save(run(build(config), max_steps=9), folder / "faults.state", config)
    runs = list(read_sweep(folder / "sweep.toml"))
    settings = [f"config.{name}" for name in sorted(runs[0])]
    with open_results(folder / "results.csv", settings) as results:
        for config in sorted(runs, key=run_key):
            results.add(run_one(config, folder))
        results.finish()
    return folder


# --- values ------------------------------------------------------------------------------------

WHOLE_NOISE = ["-1", "-7", "", "abc", "nan", "inf", "1.5", "1e3", " 3", "\u0663", "\uff11\uff12",
               "1_0", "0x10", "+4", "99999999999999999999999", "9" * 5000, "\u200b3",
               "3\u00a0", "\u00b2", "\u2460", "1\u00b9"]  # fmt: skip
"""Text given where a whole number is expected: wrong, out of range, odd unicode (some of
which Python reads as numbers: Arabic-Indic 3, fullwidth 12)."""
FLOAT_NOISE = ["0", "-0.5", "2", "nan", "-nan", "inf", "1e309", "1e-320", "", "abc", "½", "0x1p-3",
               "1,5", "\u0660.\u0665"]  # fmt: skip
SIZE_NOISE = ["0x0", "1x1", "10x-3", "99999x99999", "25000001x1", "axb", "x", "", "10X10",
              "10x10x10", " 40 x 30 ", "\u0661\u0660x\u0661\u0660", "\uff11\uff10x\uff11\uff10",
              "4e1x30", "0x30"]  # fmt: skip
STRATEGIES = ["optimal", "greedy", "random", "paper", "local-swap", "self-assembly", "mean-shift",
              "mine.py:Mine", "nope", "", "a:", ":", ":B",
              ".x:Y", "os:path", "swarmshape.core.motion:Limits", "swarmshape:Strategy",
              "missing.py:X", "notes.txt:X", "sub:X", "mine.py:", "mine.py:Optimal",
              "x" * 300, "x" * 300 + ".py:X", *HOSTILE_CLASSES]  # fmt: skip
ORDERS = ["outward", "left-to-right", "random", "", "inward", "OUTWARD"]
OPTIONS = [f"order={order}" for order in ORDERS] + [
    "startup=3", "alone=-1", "alone=1e3", "patience=²", "nope=1", "=", "order", "loss_memory=nan",
    "band=1", "band=0.5", "tau=0", "roam=1", "roam=1e9", "entering=inf", "exploring=-1",
]  # fmt: skip
"""``--set`` values: the paper's orders, self-assembly's and mean-shift's numbers, some bad."""


def whole(pick: Pick, valid: Sequence[str]) -> str:
    """Mostly a valid whole number, sometimes anything else."""
    return pick.choice(valid) if pick.integer(0, 3) else pick.choice(WHOLE_NOISE)


def number(pick: Pick, valid: Sequence[str]) -> str:
    return pick.choice(valid) if pick.integer(0, 3) else pick.choice(FLOAT_NOISE + WHOLE_NOISE)


def size(pick: Pick, valid: Sequence[str]) -> str:
    return pick.choice(valid) if pick.integer(0, 2) else pick.choice(SIZE_NOISE)


@dataclasses.dataclass(frozen=True)
class Ending:
    """How a case's process may be cut short from outside (only in a process of its own)."""

    file_limit: int | None = None
    """Bytes a file may grow to before writing fails, as on a full disk."""
    stop_after: float | None = None
    """Seconds after which the process is sent SIGTERM."""


class Paths:
    """Paths in a case's folder, made as they are drawn: valid inputs, missing files,
    folders, links that work and links that dangle, odd names; and with `isolated` (only in
    a process of its own) pipes and devices."""

    def __init__(self, pick: Pick, folder: Path, isolated: bool) -> None:
        self.pick, self.folder, self.isolated = pick, folder, isolated
        self.used_isolated = False
        self.ending = Ending()
        self._count = 0

    def _new(self, stem: str) -> str:
        self._count += 1
        return f"{stem}-{self._count}"

    def input(self, kind: str) -> str:
        """A path given where an input of `kind` (a key of `INPUTS`) is expected."""
        pick = self.pick
        valid = INPUTS[kind]
        roll = pick.integer(0, 19)
        if roll < 10:
            return pick.choice(valid)
        if roll < 12:
            return pick.choice([name for names in INPUTS.values() for name in names] + OTHERS)
        shapes = ["missing", "trailing-slash", "link", "dangling", "loop", "unicode", "long",
                  "too-long", "empty", "proc"]  # fmt: skip
        if self.isolated:
            shapes += ["fifo", "fifo", "/dev/zero", "/dev/null", "/dev/urandom"]
        odd = pick.choice(shapes)
        source = pick.choice(valid)
        suffix = Path(source).suffix
        if odd == "missing":
            return self._new("nope") + suffix
        if odd == "trailing-slash":
            return source + "/"
        if odd == "link":
            absolute = os.path.abspath(self.folder / source)
            return self._link(absolute if pick.integer(0, 1) else source)
        if odd == "dangling":
            return self._link(self._new("gone") + suffix)
        if odd == "loop":
            return self._loop(suffix)
        if odd in ("unicode", "long"):
            stem = "ψ ✓ é\u200b" if odd == "unicode" else "l" * (250 - len(suffix))
            name = stem + suffix
            shutil.copyfile(self.folder / source, self.folder / name)
            return name
        if odd == "too-long":
            return "t" * 300 + suffix
        if odd == "empty":
            return ""
        if odd == "proc":
            return "/proc/self/status"
        self.used_isolated = True
        if odd == "fifo":
            name = self._new("pipe") + suffix
            os.mkfifo(self.folder / name)
            return name
        return odd

    def output(self, suffixes: Sequence[str]) -> str:
        """A path given where an output file is expected (its name ends in one of `suffixes`)."""
        pick = self.pick
        suffix = pick.choice(suffixes)
        roll = pick.integer(0, 19)
        if roll < 10:
            return self._new("out") + suffix
        odd = pick.choice(["input", "input", "folder", "missing-folder", "fifo", "dangling",
                           "link", "device", "too-long", "unicode", "subfolder", "empty",
                           "other-suffix", "trailing-slash", "loop"])  # fmt: skip
        if odd == "input":
            return pick.choice([name for names in INPUTS.values() for name in names] + OTHERS[:2])
        if odd == "folder":
            return pick.choice(["sub", "."])
        if odd == "missing-folder":
            return f"{self._new('nowhere')}/out{suffix}"
        if odd == "fifo":
            name = self._new("pipe") + suffix
            os.mkfifo(self.folder / name)
            return name
        if odd == "dangling":
            return self._link(self._new("target") + suffix)
        if odd == "link":
            return self._link(pick.choice(["notes.txt", "shape.png", "results.csv"]))
        if odd == "loop":
            return self._loop(suffix)
        if odd == "device":
            return pick.choice(["/dev/null", "/dev/full"])
        if odd == "too-long":
            return "o" * 300 + suffix
        if odd == "unicode":
            return self._new("ψ ✓ é") + suffix
        if odd == "subfolder":
            return f"sub/{self._new('out')}{suffix}"
        if odd == "empty":
            return ""
        if odd == "trailing-slash":
            return self._new("out") + suffix + "/"
        return self._new("out") + pick.choice([".txt", "", ".JSON", ".gif.bak", "."])

    def folder_output(self) -> str:
        """A path given where an output folder is expected (``--frames``, ``plot --out``)."""
        odd = self.pick.choice(["new", "new", "new", "sub", ".", "shape.png", "nested", "fifo",
                                "dangling", "/dev/null", "too-long", "empty-folder",
                                "loop"])  # fmt: skip
        if odd == "new":
            return self._new("frames")
        if odd == "nested":
            return f"{self._new('a')}/b/c"
        if odd == "fifo":
            name = self._new("pipe")
            os.mkfifo(self.folder / name)
            return name
        if odd == "dangling":
            return self._link(self._new("gone"))
        if odd == "too-long":
            return "f" * 300
        if odd == "loop":
            return self._loop("")
        if odd == "empty-folder":
            name = self._new("empty")
            (self.folder / name).mkdir()
            return name
        return odd

    def dask(self) -> str:
        """A Dask address, which only a process of its own may try: a Dask client that failed
        leaves threads behind, and after a few a new one fails in a way no user meets."""
        self.used_isolated = True
        return self.pick.choice(["", "nope", "tcp://", "tcp://a:b", "::", "nope://x:1"])

    def special(self, suffix: str) -> str:
        """A pipe (named with `suffix`) or a device: an input that is no file."""
        self.used_isolated = True
        odd = self.pick.choice(["fifo", "fifo", "/dev/zero", "/dev/null", "/dev/urandom"])
        if odd == "fifo":
            odd = self._new("pipe") + suffix
            os.mkfifo(self.folder / odd)
        return odd

    def _loop(self, suffix: str) -> str:
        """A symlink to itself, or one of two links to each other."""
        name = self._new("loop") + suffix
        if self.pick.integer(0, 1):
            (self.folder / name).symlink_to(name)
        else:
            other = self._new("loop") + suffix
            (self.folder / name).symlink_to(other)
            (self.folder / other).symlink_to(name)
        return name

    def _link(self, target: str) -> str:
        name = self._new("link") + Path(target).suffix
        (self.folder / name).symlink_to(target)
        return name


# --- command lines -----------------------------------------------------------------------------

MAX_STEPS = ["0", "1", "2", "3", "5", "8", "13", "20"]
"""A run's --max-steps: always small, so that every run is short."""


def run_options(pick: Pick, paths: Paths) -> dict[str, Callable[[], list[str]]]:
    """Every option of ``run`` with a drawer of its values, valid ones kept small."""
    return {
        "--seed": lambda: [whole(pick, ["0", "1", "7", str(2**63 - 1), str(2**63)])],
        "--agents": lambda: [whole(pick, ["1", "2", "5", "20", "60", "1000001"])],
        "--strategy": lambda: [pick.choice(STRATEGIES)],
        "--set": lambda: [pick.choice(OPTIONS)],
        "--cells": lambda: [whole(pick, ["1", "2", "5", "12", "40", "5000", "100000", "10**9"])],
        "--threshold": lambda: [number(pick, ["0.3", "0.5", "0.7", "0.999", "1e-9"])],
        "--invert": list,
        "--fit": lambda: [pick.choice(["agents", "agents", "cells", ""])],
        "--preview": list,
        "--arena": lambda: [size(pick, ["40x30", "20x12", "9x9", "12x40", "1x25000000"])],
        "--max-speed": lambda: [number(pick, ["0.5", "1", "0.25", "0.001"])],
        "--max-accel": lambda: [number(pick, ["0.125", "0.001", "0.5", "0.25"])],
        "--speed": lambda: [number(pick, ["8", "1", "0.5"])],
        "--start": lambda: [paths.input("start")],
        "--load-state": lambda: [paths.input("state")],
        "--record": lambda: [paths.output([".gif", ".webp", ".png", ".GIF", ".txt"])],
        "--frames": lambda: [paths.folder_output()],
        "--record-every": lambda: [whole(pick, ["1", "2", "5", "99999999999999999999"])],
        "--record-size": lambda: [size(pick, ["64x48", "80x60", "96x64"])],
        "--trace": lambda: [paths.output([".csv", ".txt", ""])],
        "--trace-every": lambda: [whole(pick, ["1", "3", "99999999999999999999"])],
        "--save-state": lambda: [paths.output([".state", ".npz", ""])],
        "--positions": lambda: [paths.output([".npz", ".csv", ".NPZ", ".txt"])],
        "--positions-every": lambda: [whole(pick, ["1", "4"])],
        "--metrics": lambda: [paths.output([".json", ".txt", ""])],
        "--fail": lambda: [f"{number(pick, ['0.2', '0.5', '3'])}@{whole(pick, ['0', '2'])}"],
        "--stall": lambda: [f"{number(pick, ['0.3', '1'])}@{whole(pick, ['1', '3'])}"],
        "--fail-region": lambda: [
            f"{','.join(whole(pick, ['0', '2', '4']) for _ in range(pick.integer(2, 5)))}"
            f"@{whole(pick, ['0', '3'])}"
        ],
        "--failure-rate": lambda: [number(pick, ["0.002", "0.05", "0"])],
        "--force": list,
        "--colour": lambda: ["red"],
        "-x": list,
        "--": list,
    }


def spell(pick: Pick, flag: str, values: list[str]) -> list[str]:
    """An option as a user might type it: ``--opt value``, ``--opt=value``, or abbreviated."""
    if flag.startswith("--") and len(flag) > 4 and pick.integer(0, 9) == 0:
        flag = flag[: pick.integer(3, len(flag) - 1)]
    if values and pick.integer(0, 4) == 0:
        return [f"{flag}={values[0]}", *values[1:]]
    return [flag, *values]


def options(pick: Pick, drawers: dict[str, Callable[[], list[str]]], most: int) -> list[str]:
    """Up to `most` options from `drawers`, in any order, now and then one twice."""
    names = sorted(drawers)
    argv: list[str] = []
    for _ in range(pick.integer(0, most)):
        flag = pick.choice(names)
        argv += spell(pick, flag, drawers[flag]())
    return argv


def headless(pick: Pick, argv: list[str]) -> list[str]:
    """A run's command line made safe to run in a test: no window, few steps."""
    steps = pick.choice(MAX_STEPS) if pick.integer(0, 9) else pick.choice(["-1", "", "x", "1.5"])
    return [*argv, "--headless", "--max-steps", steps]


def run_line(pick: Pick, paths: Paths) -> list[str]:
    """``run`` with an image, a scenario, the bundled shape or a saved run, and options."""
    argv = ["run"] if pick.integer(0, 1) else []
    source = pick.choice(["image", "image", "scenario", "default", "state"])
    if source in ("image", "scenario"):
        argv.append(paths.input(source))
    elif source == "state":
        argv += ["--load-state", paths.input("state")]
    argv += options(pick, run_options(pick, paths), 6)
    return headless(pick, argv)


def preview_line(pick: Pick, paths: Paths) -> list[str]:
    drawers = run_options(pick, paths)
    image = {k: drawers[k] for k in ("--cells", "--threshold", "--invert", "--fit", "--agents")}
    source = paths.input(pick.choice(["image", "scenario"]))
    return [source, "--preview", *options(pick, image, 3)]


def sweep_line(pick: Pick, paths: Paths, file: str | None = None) -> list[str]:
    argv = ["sweep", file or paths.input("sweep")]
    drawers = {
        "--out": lambda: [paths.output([".csv", ".txt", ""])],
        "--workers": lambda: [whole(pick, ["1", "2", "99999999999999999999"])],
        "--force": list,
        "--dask": lambda: [paths.dask()],
        "--help": list,
    }
    return argv + options(pick, drawers, 3)


def plot_line(pick: Pick, paths: Paths, file: str | None = None) -> list[str]:
    argv = ["plot", file or paths.input("results")]
    drawers = {
        "--out": paths.folder_output,
        "--format": lambda: [pick.choice(["png", "svg", "pdf", "", "PNG"])],
        "--force": list,
    }
    return argv + options(pick, drawers, 3)


def check_line(pick: Pick, paths: Paths) -> list[str]:
    runs = pick.choice(["1", "2"]) if pick.integer(0, 3) else pick.choice(["0", "-1", "x", ""])
    steps = whole(pick, ["0", "5", "40"])
    strategy = pick.choice([*STRATEGIES, "hostile.py:Loops"])
    argv = ["check", strategy, "--runs", runs, "--max-steps", steps]
    if pick.integer(0, 1):
        argv += ["--seed", whole(pick, ["0", "5", "9223372036854775807", "18446744073709551616"])]
    return argv


def other_line(pick: Pick, paths: Paths) -> list[str]:
    """The small commands, help and version, and junk."""
    return pick.choice(
        [
            ["strategies"],
            ["strategies", "extra"],
            ["--help"],
            ["--version"],
            ["run", "--help"],
            ["sweep", "--help"],
            ["plot"],
            ["check"],
            ["sweep"],
            ["--headless", "--max-steps", "2", "--", "shape.png"],
            ["-h", "--max-steps", "2"],
            ["--max-steps", "2", "--headless", "shape.png", "scenario.toml"],
        ]
    )


# --- mutations of bytes, images and structured files --------------------------------------------

INTERESTING = [0, 1, -1, 2, 3, 90, 45, 4095, 4096, 1_000_001, 2**31, 2**63 - 1, 2**63, -(2**63),
               10**30, 0.0, -0.0, 0.5, 1.5, 1e-320, 1e308, float("inf"), float("-inf"),
               float("nan"), True, False, "", "x", "0", "optimal", "paper", "mine.py:Mine",
               "shape.png", "sub/dot.png", "scenario.toml", "../shape.png", "/dev/null", "sub",
               ".", "é", "a" * 300, "#zzz", "red", "rgb(999,999,999)", "hsl(999, 999%, 999%)",
               "a,b", 'a"b', "a\nb", "$x$", "shape\x00.png", [], [1], [1, 2], [1, 2, 3], ["a"],
               [[1, 2]], {}, {"x": 1}]  # fmt: skip
"""Values a mutation puts where another was: other types, edges, out of range."""


def flip_bits(pick: Pick, data: bytes) -> bytes:
    if not data:
        return data
    mutable = bytearray(data)
    for _ in range(pick.integer(1, 8)):
        mutable[pick.integer(0, len(data) - 1)] ^= 1 << pick.integer(0, 7)
    return bytes(mutable)


def truncate(pick: Pick, data: bytes) -> bytes:
    return data[: pick.integer(0, max(0, len(data) - 1))]


def duplicate(pick: Pick, data: bytes) -> bytes:
    """A stretch of the file copied somewhere else in it."""
    if not data:
        return data
    start = pick.integer(0, len(data) - 1)
    end = pick.integer(start, min(len(data), start + 256))
    at = pick.integer(0, len(data))
    return data[:at] + data[start:end] + data[at:]


def overwrite(pick: Pick, data: bytes, within: int) -> bytes:
    """A few bytes near the start (where headers are) set to edge values."""
    if not data:
        return data
    mutable = bytearray(data)
    for _ in range(pick.integer(1, 4)):
        mutable[pick.integer(0, min(within, len(data)) - 1)] = pick.choice([0, 1, 0x7F, 0x80, 0xFF])
    return bytes(mutable)


def mutate_bytes(pick: Pick, data: bytes) -> bytes:
    how = pick.choice(["flip", "truncate", "duplicate", "overwrite", "append", "nothing"])
    if how == "flip":
        return flip_bits(pick, data)
    if how == "truncate":
        return truncate(pick, data)
    if how == "duplicate":
        return duplicate(pick, data)
    if how == "overwrite":
        return overwrite(pick, data, 64)
    if how == "append":
        return data + pick.choice([b"\x00" * 100, b"garbage", data[:50], b"\xff" * 7])
    return data


FORMATS = {"PNG": ".png", "GIF": ".gif", "BMP": ".bmp", "JPEG": ".jpg", "WEBP": ".webp"}
FOREIGN = {"TIFF": ".tif", "ICO": ".ico", "PPM": ".ppm", "PCX": ".pcx", "TGA": ".tga",
           "SGI": ".sgi", "IM": ".im", "PDF": ".pdf", "EPS": ".eps"}  # fmt: skip


def picture(pick: Pick) -> Image.Image:
    """A small random shape in a random mode, ink and background."""
    height, width = pick.integer(1, 9), pick.integer(1, 9)
    bits = pick.integer(0, 2 ** (height * width) - 1)
    grid = np.array([(bits >> i) & 1 for i in range(height * width)], bool).reshape(height, width)
    scale = pick.choice([1, 1, 2, 3])
    grid = grid.repeat(scale, 0).repeat(scale, 1)
    ink, paper = pick.choice([(0, 255), (0, 255), (255, 0), (120, 135), (0, 0), (255, 255)])
    image = Image.fromarray(np.where(grid, ink, paper).astype(np.uint8))
    mode = pick.choice(["L", "1", "P", "RGB", "RGBA", "LA", "I;16", "CMYK"])
    image = image.convert(mode) if mode != "I;16" else image.convert("I").convert("I;16")
    if mode in ("RGBA", "LA") and pick.integer(0, 1):
        alpha = Image.fromarray(np.where(grid, 255, pick.choice([0, 128, 255])).astype(np.uint8))
        image.putalpha(alpha)
    return image


def encoded(pick: Pick, image: Image.Image, form: str) -> bytes:
    buffer = io.BytesIO()
    options: dict[str, Any] = {}
    if form == "GIF" and pick.integer(0, 2) == 0:
        options = {"save_all": True, "append_images": [image.transpose(Image.Transpose.ROTATE_90)]}
    try:
        image.save(buffer, format=form, **options)
    except (OSError, ValueError, KeyError):
        buffer = io.BytesIO()
        image.convert("RGB").save(buffer, format=form)
    return buffer.getvalue()


def png_chunks(data: bytes) -> list[bytes]:
    """A PNG's chunks, each with its length, type and CRC (the signature left out)."""
    chunks, at = [], 8
    while at + 8 <= len(data):
        (length,) = struct.unpack(">I", data[at : at + 4])
        chunks.append(data[at : at + 12 + length])
        at += 12 + length
    return chunks


def png_chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def edit_png(pick: Pick, data: bytes) -> bytes:
    """A PNG with an edited header (valid CRC, so the reader believes it), a chunk duplicated,
    dropped or swapped, or an extra chunk."""
    chunks = png_chunks(data)
    if not chunks:
        return data
    how = pick.choice(["header", "duplicate", "drop", "swap", "text"])
    if how == "header" and chunks[0][4:8] == b"IHDR" and len(chunks[0]) == 25:
        width, height, depth, colour, compression, filtering, interlace = struct.unpack(
            ">IIBBBBB", chunks[0][8:21]
        )
        edges = [0, 1, 2, 7, 255, 5000, 30000, 65535, 2**31 - 1, 2**32 - 1]
        field = pick.integer(0, 6)
        values = [width, height, depth, colour, compression, filtering, interlace]
        values[field] = pick.choice(edges if field < 2 else [0, 1, 2, 3, 4, 6, 8, 16, 255])
        chunks[0] = png_chunk(b"IHDR", struct.pack(">IIBBBBB", *values))
    elif how == "duplicate":
        at = pick.integer(0, len(chunks) - 1)
        chunks.insert(pick.integer(0, len(chunks)), chunks[at])
    elif how == "drop" and len(chunks) > 1:
        del chunks[pick.integer(0, len(chunks) - 1)]
    elif how == "swap" and len(chunks) > 1:
        i, j = pick.integer(0, len(chunks) - 1), pick.integer(0, len(chunks) - 1)
        chunks[i], chunks[j] = chunks[j], chunks[i]
    else:
        body = pick.choice([b"swarmshape-one-cell-per-pixel\x001", b"x" * 5000, b"", b"\xff"])
        kind = pick.choice([b"tEXt", b"zTXt", b"iCCP", b"acTL", b"tRNS"])
        chunks.insert(1, png_chunk(kind, body))
    return data[:8] + b"".join(chunks)


def edit_header(pick: Pick, data: bytes, form: str) -> bytes:
    """The declared size (or depth) of a GIF, BMP or JPEG set to an edge value."""
    mutable = bytearray(data)
    edge = pick.choice([0, 1, 255, 256, 5000, 30000, 65535])
    if form == "GIF" and len(data) >= 10:
        struct.pack_into("<H", mutable, pick.choice([6, 8]), edge)
    elif form == "BMP" and len(data) >= 30:
        field = pick.choice([(18, "<i"), (22, "<i"), (28, "<H"), (30, "<I")])
        value = pick.choice([edge, -edge, 0, 1, 4, 24, 32, 2**31 - 1]) if field[1] == "<i" else edge
        struct.pack_into(field[1], mutable, field[0], value if field[1] != "<H" else edge)
    elif form == "JPEG":
        at = data.find(b"\xff\xc0")
        if at >= 0 and at + 9 <= len(data):
            struct.pack_into(">H", mutable, at + pick.choice([5, 7]), edge)
    else:
        return overwrite(pick, data, 40)
    return bytes(mutable)


def image_bytes(pick: Pick) -> tuple[bytes, str]:
    """An image file (or a foreign file named like one), mutated; and its file name suffix."""
    image = picture(pick)
    if pick.integer(0, 7) == 0:
        form = pick.choice(sorted(FOREIGN))
        try:
            data = encoded(pick, image, form)
        except (OSError, ValueError, KeyError):  # a writer this Pillow lacks (EPS needs gs)
            data = b"%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 10 10\nshowpage\n"
        data = pick.choice([data, data, mutate_bytes(pick, data)])
        return data, pick.choice([*FORMATS.values(), FOREIGN[form]])
    form = pick.choice(sorted(FORMATS))
    data = encoded(pick, image, form)
    how = pick.choice(["none", "bytes", "bytes", "header", "chunks"])
    if how == "bytes":
        data = mutate_bytes(pick, data)
    elif how == "header":
        data = edit_header(pick, data, form)
    elif how == "chunks" and form == "PNG":
        data = edit_png(pick, data)
    suffix = FORMATS[form] if pick.integer(0, 5) else pick.choice([*FORMATS.values(), ""])
    return data, suffix


def paths_in(tree: Any, here: tuple = ()) -> Iterator[tuple]:
    """Every place in a tree of dicts and lists, as a tuple of keys and indices."""
    yield here
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from paths_in(value, (*here, key))
    elif isinstance(tree, list):
        for index, value in enumerate(tree):
            yield from paths_in(value, (*here, index))


def mutate_tree(pick: Pick, tree: dict) -> dict:
    """One edit somewhere in a tree: a value of another type or out of range, a key renamed
    or removed, a list for a value or a value for a list, a table for a value."""
    tree = json.loads(json.dumps(tree))
    places = [place for place in paths_in(tree) if place]
    if not places:
        tree[pick.choice(["x", "groups", "shapes"])] = pick.choice(INTERESTING)
        return tree
    place = pick.choice(places)
    parent = tree
    for key in place[:-1]:
        parent = parent[key]
    last = place[-1]
    how = pick.choice(["value", "value", "value", "rename", "remove", "listed", "unlisted",
                       "table", "add"])  # fmt: skip
    if how == "rename" and isinstance(parent, dict):
        name = pick.choice([last[:-1], last.upper(), last + "s", "colour_", "Shape", ""])
        parent[name] = parent.pop(last)
    elif how == "remove":
        del parent[last]
    elif how == "listed":
        parent[last] = [parent[last]] * pick.integer(0, 3)
    elif how == "unlisted" and isinstance(parent[last], list) and parent[last]:
        parent[last] = parent[last][0]
    elif how == "table":
        parent[last] = {"value": parent[last]}
    elif how == "add" and isinstance(parent, dict):
        key = pick.choice(["extra", "seed", "agents", "pose", "rotation"])
        parent[key] = pick.choice(INTERESTING)
    else:
        parent[last] = pick.choice(INTERESTING)
    return tree


def toml_value(value: Any) -> str:
    """`value` as inline TOML (nan and inf included)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(str(value), repr(value))
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def toml_text(tree: dict) -> str:
    return "".join(f"{json.dumps(key)} = {toml_value(value)}\n" for key, value in tree.items())


def mutate_text(pick: Pick, text: str) -> bytes:
    """A text file edited line by line, or its bytes damaged, or nested deeper than any
    reader recurses."""
    lines = text.splitlines(keepends=True) or [""]
    how = pick.choice(["drop", "repeat", "garbage", "deep", "bom", "crlf", "latin", "bytes",
                       "nul"])  # fmt: skip
    at = pick.integer(0, len(lines) - 1)
    if how == "drop":
        del lines[at]
    elif how == "repeat":
        lines.insert(at, lines[at])
    elif how == "garbage":
        lines.insert(at, pick.choice(["[[[\n", "= 3\n", '"\n', "x = [1,\n", "\t\x0c\n", "}\n"]))
    elif how == "deep":
        depth = pick.choice([50, 600, 3000, 100_000])
        lines.append(f"deep = {'[' * depth}{']' * depth}\n")
    elif how == "bom":
        lines.insert(0, "\ufeff")
    elif how == "crlf":
        lines = [line.replace("\n", "\r\n") for line in lines]
    elif how == "latin":
        return "".join(lines).encode("latin-1", "replace") + b"\xe9\xff\n"
    elif how == "nul":
        lines.insert(at, "\x00\n")
    else:
        return mutate_bytes(pick, "".join(lines).encode())
    return "".join(lines).encode("utf-8", "surrogatepass")


def mutated_toml(pick: Pick, text: str) -> bytes:
    import tomllib

    tree = tomllib.loads(text)
    for _ in range(pick.integer(1, 3)):
        tree = mutate_tree(pick, tree)
    written = toml_text(tree)
    return mutate_text(pick, written) if pick.integer(0, 3) == 0 else written.encode()


CSV_CELLS = ["", "-1", "0", "1e3", "99999999999999999999", "nan", "x", "\u0663", " 4", "1.0",
             "2**3", "[]", "[nan]", "[1e999]", '{"a": 1}', "[" * 5000 + "]" * 5000, "null", "true",
             "[0.5, 1]", "[-1]", "[" + ", ".join(["0.5"] * 2000) + "]", "$\\frac{1}{0$",
             "a$b$c"]  # fmt: skip


def mutated_csv(pick: Pick, text: str) -> bytes:
    """A CSV with a cell, a row or its header changed, or damaged as text."""
    rows = list(csv.reader(io.StringIO(text)))
    how = pick.choice(["cell", "cell", "cell", "row", "header", "text"])
    if how == "text" or not rows:
        return mutate_text(pick, text)
    r = pick.integer(0, len(rows) - 1)
    if how == "cell" and rows[r]:
        rows[r][pick.integer(0, len(rows[r]) - 1)] = pick.choice(CSV_CELLS)
    elif how == "row":
        what = pick.choice(["drop", "repeat", "short", "long", "empty", "many"])
        if what == "drop":
            del rows[r]
        elif what == "repeat":
            rows.insert(r, list(rows[r]))
        elif what == "short" and rows[r]:
            rows[r] = rows[r][:-1]
        elif what == "long":
            rows[r] = [*rows[r], "extra"]
        elif what == "empty":
            rows.insert(r, [])
        else:
            rows += [list(rows[-1])] * 3000
    elif how == "header":
        header = rows[0]
        if header:
            i = pick.integer(0, len(header) - 1)
            header[i] = pick.choice(["", header[i].upper(), header[(i + 1) % len(header)], "é"])
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator=pick.choice(["\n", "\n", "\r\n"])).writerows(rows)
    return buffer.getvalue().encode()


def state_members(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    with np.load(path, allow_pickle=False) as stored:
        members = {name: stored[name] for name in stored.files}
    return json.loads(members.pop("manifest").tobytes()), members


def mutated_array(pick: Pick, array: np.ndarray) -> np.ndarray:
    """The array with another dtype, shape or values (out of range, NaN, huge)."""
    how = pick.choice(["dtype", "shape", "values", "values", "empty", "scalar", "order"])
    if how == "dtype":
        with np.errstate(invalid="ignore"):  # NaN to integers: the mutation wants any value
            return array.astype(pick.choice(["<f4", "<i4", "|b1", "<u8", ">i8", "<f8", "<i8",
                                              "<U3", "|i1", "<c16"]))  # fmt: skip
    if how == "shape":
        flat = array.reshape(-1)
        return pick.choice([flat, flat[:-1], np.concatenate([flat, flat[:1]]), flat[:, None],
                            array.reshape(1, *array.shape)])  # fmt: skip
    if how == "empty":
        return array[:0]
    if how == "scalar":
        return np.array(array.reshape(-1)[0] if array.size else 0, dtype=array.dtype)
    if how == "order":
        return np.asfortranarray(array.T)
    changed = array.copy()
    if changed.size:
        index = pick.integer(0, changed.size - 1)
        kind = changed.dtype.kind
        if kind == "f":
            edges = [np.nan, np.inf, -np.inf, -1.0, 1e300, 2.0, 0.0]
        elif kind == "b":
            edges = [not bool(changed.reshape(-1)[index])]
        else:
            info = np.iinfo(changed.dtype)
            edges = [info.min, info.max, -1, -2, 0, 1, 2, 5, 10_000]
            edges = [e for e in edges if info.min <= e <= info.max]
        changed.reshape(-1)[index] = pick.choice(edges)
    return changed


def state_bytes(
    manifest: dict, arrays: dict[str, np.ndarray], *, compressed: bool = True, deep: bool = False
) -> bytes:
    """A state file of `manifest` and `arrays`, its list of arrays and its checksum made to
    match (unless the manifest holds what no checksum can: NaN); `deep` nests it 3,000 deep."""
    from swarmshape.io.checkpoint import _checksum

    manifest["arrays"] = sorted(arrays)
    manifest.pop("checksum", None)
    try:
        manifest["checksum"] = _checksum(manifest, arrays)
    except (ValueError, TypeError):
        manifest["checksum"] = "0" * 64
    text = json.dumps(manifest, sort_keys=True)
    if deep:
        text = text.replace("[[[", "[" * 3000, 1).replace("]]]", "]" * 3000, 1)
    buffer = io.BytesIO()
    save = np.savez_compressed if compressed else np.savez
    save(buffer, manifest=np.frombuffer(text.encode(), np.uint8), **arrays)
    return buffer.getvalue()


def changed_state(path: Path, changes: dict[str, Any]) -> bytes:
    """The state file at `path` with some values or arrays replaced, its checksum matching."""
    manifest, arrays = state_members(path)
    for key, value in changes.items():
        (arrays if isinstance(value, np.ndarray) else manifest["values"])[key] = value
    return state_bytes(manifest, arrays)


def mutated_state(pick: Pick, path: Path) -> bytes:
    """A state file damaged as bytes, or rewritten with a matching checksum around a changed
    value, array, member list or manifest, so that only its contents can refuse it."""
    if pick.integer(0, 3) == 0:
        return mutate_bytes(pick, path.read_bytes())
    manifest, arrays = state_members(path)
    how = pick.choice(["value", "value", "array", "array", "array", "drop", "extra", "head",
                       "deep", "raw", "bomb"])  # fmt: skip
    values = manifest["values"]
    if how == "value":
        key = pick.choice(sorted(values))
        values[key] = pick.choice([*INTERESTING, None, {"arrays": 3}, {"arrays": -1}])
    elif how == "array":
        key = pick.choice(sorted(arrays))
        arrays[key] = mutated_array(pick, arrays[key])
    elif how == "drop":
        container = pick.choice(["values", "arrays"])
        if container == "values":
            del values[pick.choice(sorted(values))]
        else:
            del arrays[pick.choice(sorted(arrays))]
    elif how == "extra":
        arrays[pick.choice(["swarm.extra", "manifest.npy", "swarm.cell.x"])] = np.zeros(3)
    elif how == "head":
        manifest[pick.choice(["format", "version", "values"])] = pick.choice(INTERESTING)
    elif how == "deep":
        values[pick.choice(sorted(values))] = json.loads("[" * 50 + "]" * 50)
    elif how == "bomb":  # 64 MB of zeros, which pack to a few kB (issue 29: 3 GB took 3 GB)
        arrays[pick.choice(sorted(arrays))] = np.zeros((pick.choice([1, 2000]), 4000), np.float64)
    data = state_bytes(manifest, arrays, compressed=pick.integer(0, 1) == 1, deep=how == "deep")
    return raw_member(data, pick.choice(["manifest", *sorted(arrays)])) if how == "raw" else data


def raw_member(data: bytes, name: str) -> bytes:
    """A state file with the member `name` stored as plain bytes (its JSON), not as a .npy."""
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    manifest = members["manifest.npy"]
    members[f"{name}.npy"] = manifest[manifest.index(b"{") :]
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as archive:
        for member, content in members.items():
            archive.writestr(member, content)
    return out.getvalue()


# --- the kinds of case -------------------------------------------------------------------------


def image_case(pick: Pick, paths: Paths) -> list[str]:
    data, suffix = image_bytes(pick)
    name = "fuzz" + suffix
    (paths.folder / name).write_bytes(data)
    drawers = run_options(pick, paths)
    image = {k: drawers[k] for k in ("--cells", "--threshold", "--invert", "--fit", "--agents")}
    argv = [name, *options(pick, image, 2)]
    return [*argv, "--preview"] if pick.integer(0, 4) == 0 else headless(pick, argv)


SCENARIO_FAULTS = ["", "", "failure_rate = 0.002\n", "failure_rate = 0.05\n",
                   "[[faults]]\nstep = 0\nkind = 'remove'\namount = 1\n",
                   "[[faults]]\nstep = 2\nkind = 'stall'\namount = 0.3\n"]  # fmt: skip
"""Faults for the scenario's two groups (issue 29: a group re-formed smaller after a fault
renumbered the other group's targets, and a robot went for one past the end)."""


def scenario_case(pick: Pick, paths: Paths) -> list[str]:
    text = SCENARIO.replace("[[groups]]", pick.choice(SCENARIO_FAULTS) + "[[groups]]", 1)
    (paths.folder / "fuzz.toml").write_bytes(mutated_toml(pick, text))
    return headless(pick, ["fuzz.toml", *options(pick, run_options(pick, paths), 1)])


def start_case(pick: Pick, paths: Paths) -> list[str]:
    text = (paths.folder / "start.csv").read_text()
    (paths.folder / "fuzz.csv").write_bytes(mutated_csv(pick, text))
    return headless(pick, ["shape.png", "--seed", "0", "--start", "fuzz.csv"])


def state_case(pick: Pick, paths: Paths) -> list[str]:
    source = paths.folder / pick.choice(INPUTS["state"])
    (paths.folder / "fuzz.state").write_bytes(mutated_state(pick, source))
    argv = ["--load-state", "fuzz.state"]
    extra = pick.choice([[], [], ["--save-state", "fuzz.state"], ["--metrics", "m.json"],
                         ["--metrics", "fuzz.state"], ["--trace", "fuzz.state", "--force"],
                         ["--trace", "t.csv", "--positions", "p.npz"], ["--strategy", "paper"],
                         ["--record", "r.gif", "--record-size", "64x48"]])  # fmt: skip
    return headless(pick, argv + extra)


def sweep_case(pick: Pick, paths: Paths) -> list[str]:
    """A mutated sweep file. One that holds more than `LONG_SWEEP` valid runs is sent SIGTERM
    on the way, as a user stops a sweep, rather than waited for: the 16,384 runs of
    ``seeds = 4096`` took half an hour (seed 38, case 8437), which is work, not a hang."""
    from swarmshape.errors import InputError
    from swarmshape.experiments.sweep import read_sweep

    path = paths.folder / "fuzz-sweep.toml"
    path.write_bytes(mutated_toml(pick, SWEEP))
    argv = sweep_line(pick, paths, path.name)
    try:
        runs = len(read_sweep(path))
    except InputError:
        runs = 0  # refused: at once, whatever it holds
    if runs > LONG_SWEEP:
        paths.used_isolated = True
        paths.ending = Ending(stop_after=pick.choice([1.0, 5.0, 20.0]))
    return argv


def results_case(pick: Pick, paths: Paths) -> list[str]:
    """A damaged results file, given to ``plot``, or to a sweep to resume into."""
    text = (paths.folder / "results.csv").read_text()
    (paths.folder / "fuzz-results.csv").write_bytes(mutated_csv(pick, text))
    if pick.integer(0, 2) == 0:
        return ["sweep", "sweep.toml", "--out", "fuzz-results.csv"]
    return plot_line(pick, paths, "fuzz-results.csv")


def special_case(pick: Pick, paths: Paths) -> list[str]:
    """A pipe or a device where a command reads a file: it must be refused, not read (a pipe
    would hang the read, /dev/zero fill the memory)."""
    where = pick.choice(["image", "scenario", "start", "state", "sweep", "results", "strategy",
                         "check", "scenario shape", "sweep shape", "sweep out",
                         "plot out"])  # fmt: skip
    if where in ("image", "scenario"):
        return headless(pick, [paths.special(".png" if where == "image" else ".toml")])
    if where == "start":
        return headless(pick, ["shape.png", "--start", paths.special(".csv")])
    if where == "state":
        return headless(pick, ["--load-state", paths.special(".state")])
    if where == "sweep":
        return ["sweep", paths.special(".toml")]
    if where == "results":
        return ["plot", paths.special(".csv")]
    if where in ("strategy", "check"):
        code = paths.special(".py") + ":Mine"
        return (
            ["check", code, "--runs", "1"]
            if where == "check"
            else headless(pick, ["shape.png", "--strategy", code])
        )
    if where == "scenario shape":
        text = SCENARIO.replace('"shape.png"', json.dumps(paths.special(".png")))
        (paths.folder / "fuzz.toml").write_text(text)
        return headless(pick, ["fuzz.toml"])
    if where == "sweep shape":
        text = SWEEP.replace('"shape.png"', json.dumps(paths.special(".png")))
        (paths.folder / "fuzz-sweep.toml").write_text(text)
        return ["sweep", "fuzz-sweep.toml"]
    if where == "sweep out":
        return ["sweep", "sweep.toml", "--out", paths.special(".csv")]
    return ["plot", "results.csv", "--out", paths.special("")]


OUTPUTS = {"--metrics": ".json", "--trace": ".csv", "--positions": ".csv", "--record": ".gif",
           "--save-state": ".state", "--frames": ""}  # fmt: skip


def ending_case(pick: Pick, paths: Paths) -> list[str]:
    """A run with outputs that runs out of disk (a file size limit) or is sent SIGTERM on the
    way: whatever it wrote is whole, and it leaves no temporary file."""
    paths.used_isolated = True
    if pick.integer(0, 1):
        # not below what the case's own stdout and stderr take: those are files too
        paths.ending = Ending(file_limit=pick.choice([2_000, 5_000, 20_000, 200_000]))
    else:
        paths.ending = Ending(stop_after=pick.choice([0.0, 0.05, 0.2, 0.5, 1.0, 2.0]))
    argv = ["shape.png", "--cells", pick.choice(["7", "16", "30"]), "--strategy",
            pick.choice(["optimal", "paper", "random"]), "--headless", "--max-steps",
            pick.choice(["5", "50", "400"])]  # fmt: skip
    for option, suffix in OUTPUTS.items():
        if pick.integer(0, 1):
            if option == "--positions":
                suffix = pick.choice([".csv", ".npz"])
            argv += [option, paths._new("out") + suffix]
    return argv


def command_case(pick: Pick, paths: Paths) -> list[str]:
    line = pick.choice([run_line, run_line, run_line, preview_line, check_line, other_line,
                        sweep_line, plot_line])  # fmt: skip
    return line(pick, paths)


KINDS: dict[str, Callable[[Pick, Paths], list[str]]] = {
    "command line": command_case,
    "image": image_case,
    "scenario": scenario_case,
    "start cells": start_case,
    "state file": state_case,
    "sweep file": sweep_case,
    "sweep results": results_case,
    "pipe or device": special_case,
    "full disk or signal": ending_case,
}
"""Every kind of case; "pipe or device" and "full disk or signal" cases are always isolated."""


@dataclasses.dataclass
class Case:
    kind: str
    argv: list[str]
    folder: Path
    isolated: bool
    """It reads a pipe or a device, or is cut short: run it only in a process of its own, with
    limits."""
    ending: Ending = Ending()

    def command(self) -> str:
        """How to run it again by hand."""
        return f"cd {shlex.quote(str(self.folder))} && swarmshape {shlex.join(self.argv)}"


def make_case(pick: Pick, kind: str, material: Path, folder: Path, isolated: bool) -> Case:
    """A fresh copy of `material` in `folder` (which must not exist), and a case of `kind` in it."""
    shutil.copytree(material, folder, symlinks=True)
    paths = Paths(pick, folder, isolated)
    argv = KINDS[kind](pick, paths)
    return Case(kind, argv, folder, paths.used_isolated, paths.ending)


# --- running a case ----------------------------------------------------------------------------


@dataclasses.dataclass
class Outcome:
    status: int | None
    """The exit status; None if the case did not finish in time."""
    stdout: str
    stderr: str
    seconds: float


class Hung(BaseException):
    """A case ran out of time (a BaseException: nothing in swarmshape may catch it)."""


def exit_status(argv: list[str]) -> int:
    """Run the command line as ``swarmshape`` would, and return its exit status."""
    from swarmshape.cli import main

    try:
        return main(list(argv))
    except SystemExit as leaving:  # argparse: --help, --version, a mistake
        code = leaving.code
        return code if isinstance(code, int) else (0 if code is None else 1)


@contextlib.contextmanager
def inside(folder: Path) -> Iterator[None]:
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(before)


@contextlib.contextmanager
def descriptors_to(streams: Sequence[Any]) -> Iterator[None]:
    """File descriptors 1 and 2 (what C libraries print to) into `streams`, for a while."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        for fd, stream in zip((1, 2), streams, strict=True):
            os.dup2(stream.fileno(), fd)
        yield
    finally:
        for fd, kept in zip((1, 2), saved, strict=True):
            os.dup2(kept, fd)
            os.close(kept)


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise `Hung` after `seconds` (on the main thread, where signals arrive; elsewhere no
    limit)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.alarm(max(1, int(seconds)))
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def run_here(case: Case, timeout: float = TIMEOUT) -> Outcome:
    """Run `case` in this process, its output captured at the file descriptors too."""
    text = [io.StringIO(), io.StringIO()]
    started = time.perf_counter()
    status: int | None = None
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        with (
            descriptors_to([out, err]),
            inside(case.folder),
            contextlib.redirect_stdout(text[0]),
            contextlib.redirect_stderr(text[1]),
            contextlib.suppress(Hung),
            time_limit(timeout),
        ):
            status = exit_status(case.argv)
        captured = []
        for stream, python in zip((out, err), text, strict=True):
            stream.seek(0)
            captured.append(python.getvalue() + stream.read().decode("utf-8", "replace"))
    return Outcome(status, *captured, time.perf_counter() - started)


def _hang(*_: object) -> None:
    raise Hung


MEMORY = 3 * 2**30
"""Address space a forked case may add to its parent's, so a runaway read fails instead of
taking the machine's memory."""


class Forked:
    """`case` running in a forked copy of this process (swarmshape already imported), with
    its memory and time limited: what a case that reads a pipe or a device needs. Crash logs
    go to `logs`."""

    def __init__(self, case: Case, timeout: float = TIMEOUT, logs: Path | None = None) -> None:
        self.streams = [tempfile.TemporaryFile() for _ in "12"]  # noqa: SIM115 (poll closes them)
        sys.stdout.flush()
        sys.stderr.flush()
        self.started = time.perf_counter()
        self.deadline = self.started + timeout
        self.stop_at = case.ending.stop_after
        self.pid = os.fork()
        if self.pid == 0:
            code = 1
            try:
                code = self._child(case, logs)
            finally:
                os._exit(code)

    def _child(self, case: Case, logs: Path | None) -> int:
        os.setsid()  # its own process group, so that a timeout ends its sweep's workers too
        os.dup2(self.streams[0].fileno(), 1)
        os.dup2(self.streams[1].fileno(), 2)
        os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
        # print() goes where the descriptors go, not to a capture of the parent's (pytest's)
        sys.stdout, sys.stderr = (open(fd, "w", buffering=1, closefd=False) for fd in (1, 2))  # noqa: SIM115
        with open("/proc/self/statm") as statm:
            pages = int(statm.read().split()[0])
        limit = pages * os.sysconf("SC_PAGE_SIZE") + MEMORY
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        if case.ending.file_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (case.ending.file_limit,) * 2)
        if logs is not None:
            tempfile.tempdir = str(logs)
        os.chdir(case.folder)
        code = exit_status(case.argv)
        sys.stdout.flush()
        sys.stderr.flush()
        return code

    def poll(self) -> Outcome | None:
        """The outcome, once the case has ended (or was ended for taking too long)."""
        done, wait_status = os.waitpid(self.pid, os.WNOHANG)
        status: int | None = None
        due = self.stop_at is not None and time.perf_counter() > self.started + self.stop_at
        if not done and due:
            os.kill(self.pid, signal.SIGTERM)
            self.stop_at = None
        if done:
            status = os.waitstatus_to_exitcode(wait_status)
        elif time.perf_counter() > self.deadline:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.pid, signal.SIGKILL)
            os.waitpid(self.pid, 0)
        else:
            return None
        captured = []
        for stream in self.streams:
            stream.seek(0)
            captured.append(stream.read().decode("utf-8", "replace"))
            stream.close()
        return Outcome(status, *captured, time.perf_counter() - self.started)


def run_forked(case: Case, timeout: float = TIMEOUT) -> Outcome:
    """Run `case` in a `Forked` process and wait for it."""
    forked = Forked(case, timeout)
    while (outcome := forked.poll()) is None:
        time.sleep(0.005)
    return outcome


# --- what an outcome may do --------------------------------------------------------------------

Entry = tuple


def snapshot(folder: Path) -> dict[str, Entry]:
    """Every entry under `folder` (links not followed): its kind, and for a file its size,
    modification time and content hash."""
    entries: dict[str, Entry] = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = os.path.join(root, name)
            relative = os.path.relpath(path, folder)
            info = os.lstat(path)
            if stat.S_ISLNK(info.st_mode):
                entries[relative] = ("link", os.readlink(path))
            elif stat.S_ISDIR(info.st_mode):
                entries[relative] = ("folder",)
            elif stat.S_ISREG(info.st_mode):
                with open(path, "rb") as handle:
                    digest = hashlib.sha256(handle.read()).hexdigest()
                entries[relative] = ("file", info.st_size, info.st_mtime_ns, digest)
            else:
                entries[relative] = ("other", stat.S_IFMT(info.st_mode))
    return entries


def parsed(argv: list[str]) -> tuple[str, Any] | None:
    """The command and options as swarmshape's own grammar reads `argv`; None if it refuses."""
    from swarmshape.cli import build_parser

    argv = list(argv)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help", "--version")):
        argv.insert(0, "run")
    quiet = io.StringIO()
    try:
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
            args = build_parser().parse_args(argv)
    except SystemExit:
        return None
    return args.command, args


class Named:
    """The outputs a command line names, as paths relative to its case's folder: only these
    may change."""

    def __init__(self, case: Case) -> None:
        self.root = os.path.realpath(case.folder)
        self.files: set[str] = set()
        self.folders: set[str] = set()
        """``--frames`` folders: they may gain and lose frame files."""
        self.plot_folders: set[str] = set()
        """``plot --out`` folders: made with their parents."""
        self.keeps_rows: str | None = None
        """A sweep's existing results file, given without --force: its lines must stay."""
        self._old_lines: set[bytes] = set()
        self.written: dict[str, str] = {}
        """What a headless run that ends (exit 0 or 3) must have written: path -> option."""
        self.summary = False
        """Whether the command is a headless run, which ends in a summary line."""
        self.ending = case.ending
        self.sweep: tuple[Path, Path] | None = None
        """A sweep's file and its results file."""
        self.inputs: set[str] = set()
        """Files the run reads: never changed, even when named as an output with --force
        (but a state saved over the one it resumes)."""
        found = parsed(case.argv)
        self.command = found[0] if found else None
        if found is None:
            return
        command, args = found
        if command in ("run", "edit"):
            self.summary = command == "run" and args.headless and not args.preview
            self._inputs(case.folder, args)
            for name in ("metrics", "record", "trace", "save_state", "positions"):
                self._file(getattr(args, name, None))
                if getattr(args, name, None) is not None and self.summary:
                    self.written[os.path.join(self.root, getattr(args, name))] = name
            if args.frames is not None:
                self.folders.add(self._relative(args.frames))
        elif command == "sweep":
            if args.out is None and not args.file.name:  # no file, so no results beside it
                return
            out = args.out or args.file.with_suffix(".csv")
            self._file(out)
            self.sweep = (case.folder / args.file, case.folder / out)
            real = Path(os.path.realpath(case.folder / out))
            self._file(real.with_name(f".{real.name}.lock"))
            with contextlib.suppress(OSError):  # not there, or a name too long
                existing = os.path.join(self.root, out)
                if not args.force and stat.S_ISREG(os.stat(existing).st_mode):
                    with open(existing, "rb") as handle:
                        self._old_lines = {line for line in handle if line.endswith(b"\n")}
                    self.keeps_rows = self._relative(out)
        elif command == "plot":
            out = args.out or args.results.parent
            self.plot_folders.add(self._relative(out))
            for form in args.format or ["png"]:
                for plot in ("coverage", "steps"):
                    self._file(out / f"{plot}.{form}")

    def _inputs(self, folder: Path, args: Any) -> None:
        """Note the files a run reads (see `inputs`)."""
        from swarmshape.runs import scenario_images

        read = [args.start if isinstance(args.start, Path) else None, args.path]
        if args.load_state is not None and args.load_state != args.save_state:
            read.append(args.load_state)
        scenario = folder / args.path if args.path is not None else None
        # a pipe named as the scenario would block the reading here (swarmshape refuses it)
        if scenario is not None and scenario.suffix.lower() == ".toml":
            with contextlib.suppress(OSError, ValueError):
                read += scenario_images(scenario) if scenario.is_file() else []
        module = (args.strategy or "").rpartition(":")[0]
        read.append(Path(module) if module.endswith(".py") else None)
        with contextlib.suppress(ValueError):  # a NUL in a name
            self.inputs = {self._relative(path) for path in read if path is not None}

    def _relative(self, path: Path | str) -> str:
        real = os.path.realpath(os.path.join(self.root, path))
        return os.path.relpath(real, self.root)

    def _file(self, path: Path | None) -> None:
        """Note an output file; a symlink loop is no file to write and may not change."""
        if path is not None and not os.path.islink(os.path.realpath(self.root / path)):
            self.files.add(self._relative(path))

    def lost_rows(self) -> bytes | None:
        """A whole line the sweep's results file had and has no more (a last line cut short
        may go: its run is done again)."""
        if self.keeps_rows is None:
            return None
        try:
            with open(os.path.join(self.root, self.keeps_rows), "rb") as handle:
                now = set(handle)
        except OSError:
            now = set()
        lost = sorted(self._old_lines - now)
        return lost[0] if lost else None

    def unreadable(self, *, written: bool = True) -> str | None:
        """An output of a finished headless run that is missing or does not read back (or, not
        `written`, one that is there and does not read back: a run cut short)."""
        from swarmshape.io.checkpoint import load_state

        for path, option in self.written.items():
            if not written and not os.path.lexists(path):
                continue
            try:
                if option == "metrics":
                    assert "coverage" in json.loads(Path(path).read_text())
                elif option == "save_state":
                    load_state(Path(path))
                elif option == "record":
                    Image.open(path).verify()
                elif option == "positions" and path.lower().endswith(".npz"):
                    with np.load(path) as arrays:
                        assert arrays["position"].ndim == 3
                else:
                    assert Path(path).read_text().startswith("step,")
            except Exception as error:
                return f"--{option.replace('_', '-')} {path}: {type(error).__name__} {error}"
        return None

    def foreign_row(self) -> str | None:
        """The key of a row that a sweep which ran to its end left in its results file although
        it is none of the sweep's runs (another sweep's, or a damaged row taken for one)."""
        from swarmshape.experiments.results import read_rows
        from swarmshape.experiments.sweep import read_sweep, run_key

        if self.sweep is None:
            return None
        sweep_file, out = self.sweep
        if not out.exists():
            return None
        runs = {run_key(config) for config in read_sweep(sweep_file)}
        return next((row["run"] for row in read_rows(out) if row["run"] not in runs), None)

    def allows(self, relative: str) -> bool:
        """Whether the entry at `relative` may change."""
        real = self._relative(relative)
        if real in self.inputs:
            return False
        if relative in self.files or real in self.files:
            return True
        parent, name = os.path.split(relative)
        if relative in self.folders:
            return True
        if parent in self.folders and fnmatch.fnmatch(name, FRAME_FILES):
            return True
        return any(folder == relative or folder.startswith(relative + os.sep)
                   for folder in self.plot_folders)  # fmt: skip


def attempt(case: Case, runner: Callable[[Case], Outcome]) -> tuple[Outcome, list[str]]:
    """Run `case` with `runner` (`run_here` or `run_forked`); its outcome and its problems."""
    named = Named(case)
    before = snapshot(case.folder)
    outcome = runner(case)
    return outcome, problems(named, outcome, before, snapshot(case.folder))


def problems(
    named: Named, outcome: Outcome, before: dict[str, Entry], after: dict[str, Entry]
) -> list[str]:
    """Everything `outcome` did that it may not: see this module's docstring."""
    found = []
    status = outcome.status
    if status is None:
        found.append(f"did not finish in {outcome.seconds:.0f} s")
    elif status not in (0, 2, 3) and (named.ending.stop_after is None or status not in STOPPED):
        found.append(f"exit status {status}")
    elif status == 3 and named.command not in ("run", "check"):
        found.append(f"exit status 3 from {named.command}")
    lines = [line for line in outcome.stderr.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("swarmshape: error: ")]
    warnings = [line for line in lines if line.startswith("swarmshape: warning: ")]
    others = [line for line in lines if line not in errors + warnings and not PROGRESS.match(line)]
    if "Traceback" in outcome.stderr or "internal error" in outcome.stderr:
        found.append("a traceback or an internal error")
    if len(errors) > 1 or len(warnings) > 1 or others:
        found.append(f"{len(lines)} lines on stderr")
    if status == 2 and len(errors) != 1:
        found.append("exit status 2 without one error line")
    if status in (0, 3) and errors:
        found.append(f"exit status {status} with an error line")
    changed = sorted(p for p in before.keys() | after.keys() if before.get(p) != after.get(p))
    unasked = [path for path in changed if not named.allows(path)]
    if unasked:
        found.append(f"changed what it was not asked to: {unasked[0]}")
    new = sorted(after.keys() - before.keys())
    cut_short = named.ending != Ending()
    if status == 2 and new and not cut_short:
        found.append(f"refused, yet left {new[0]} behind")
    if cut_short and named.summary and status not in (0, 3):
        bad = named.unreadable(written=False)
        if bad:
            found.append(f"cut short, left an output that does not read back: {bad}")
    temporary = [path for path in after if os.path.basename(path).startswith(TEMP_PREFIX)]
    if temporary:
        found.append(f"left a temporary file: {temporary[0]}")
    if named.summary and status in (0, 3):
        said = "formed in" if status == 0 else "not formed after"
        if said not in outcome.stdout:
            found.append(f"exit status {status} without '{said}' in the summary")
        overlaps = OVERLAPS.search(outcome.stdout)
        if overlaps and overlaps[1] != "0":
            found.append(f"reported {overlaps[1]} overlaps, which no run has")
        bad = named.unreadable()
        if bad:
            found.append(f"wrote an output that does not read back: {bad}")
    if named.command == "sweep" and status == 0:
        from swarmshape.errors import InputError

        try:
            foreign = named.foreign_row()
        except InputError as error:  # it wrote over what it read (the harness crashed on it)
            found.append(f"left its sweep unreadable: {error}")
        else:
            if foreign:
                found.append(f"kept a row of a run the sweep does not have: {foreign[:80]}")
    lost = named.lost_rows()
    if lost:
        found.append(f"{named.keeps_rows}: lost the line {lost!r} without --force")
    return found


@dataclasses.dataclass(frozen=True)
class Found:
    """A crash the fuzz found and that was fixed; ``tests/test_fuzz.py`` replays each to keep it
    fixed. Named by where its traceback ended and its exception."""

    where: str
    """The source file, under ``src/swarmshape/``."""
    error: str
    """How the exception's line starts."""
    argv: tuple[str, ...]
    """A command line that sets it off, in the material folder."""
    state: dict[str, Any] | None = None
    """Changes to ``paper.state`` that make the ``fuzz.state`` the command line loads."""


RESUME = ("--load-state", "fuzz.state", "--headless", "--max-steps", "8")
FOUND = (
    Found("strategies/__init__.py", "ValueError: Empty module name", ("check", ":B")),
    Found("strategies/__init__.py", "TypeError: the 'package' argument is required",
          ("shape.png", "--strategy", ".x:Y", "--headless")),
    Found("strategies/__init__.py", "OSError: [Errno 36] File name too long",
          ("shape.png", "--strategy", "x" * 300 + ".py:X", "--headless")),
    Found("check.py", "AttributeError: type object 'Strategy' has no attribute 'name'",
          ("check", "swarmshape:Strategy")),
    Found("core/steering.py", "AttributeError: 'Strategy' object has no attribute 'name'",
          ("shape.png", "--strategy", "swarmshape:Strategy", "--headless")),
    Found("core/motion.py", "TypeError: '<=' not supported between instances of 'float' and",
          RESUME, {"config.max_speed": None}),
    Found("strategies/paper.py", "TypeError: len() of unsized object", RESUME,
          {"swarm.driver.strategy._sequence.0": np.array(3)}),
)  # fmt: skip

CRASH_LOG = re.compile(r"details in (\S+\.log)")
SOURCE = re.compile(r'File "[^"]*/src/swarmshape/([^"]+)", line \d+')


def crash(outcome: Outcome) -> tuple[str, str] | None:
    """For an internal error: the source file its traceback ends in and its exception line,
    from the crash log it points to (which is then removed)."""
    found = CRASH_LOG.search(outcome.stderr)
    if not found:
        return None
    try:
        text = Path(found[1]).read_text()
        Path(found[1]).unlink()
    except OSError:
        return None
    sources = SOURCE.findall(text)
    lines = text.strip().splitlines()
    return (sources[-1] if sources else "?", lines[-1] if lines else "")


def first_error_line(outcome: Outcome) -> str:
    lines = [line for line in outcome.stderr.splitlines() if line.strip()]
    return lines[0] if lines else ""

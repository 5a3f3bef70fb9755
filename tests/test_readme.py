"""The README cannot drift: its settings table is the one the code declares, every command and
snippet in its code blocks runs here as written (headless, in a temporary folder, so nothing in
the repository is written) and does what the README says, and every figure its example output
prints is what the code gives."""

from __future__ import annotations

import csv
import dataclasses
import html
import json
import re
import shlex
import shutil
import weakref
from pathlib import Path

import pygame
import pytest
from PIL import Image

from swarmshape import cli
from swarmshape.cli import settings_table
from swarmshape.config import RunConfig, configure
from swarmshape.experiments.sweep import read_sweep
from swarmshape.ui.viewer import Viewer
from tests.conftest import WHOLE_RUN_EXAMPLES, script

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()

NOT_RUNNABLE = {
    "scripts/test": "the whole suite, this test among it: 2 to 4 minutes on two cores",
    "swarmshape benchmark my_policy.py:Mine": "a policy the user writes, on all eight tasks up to "
    "10,000 robots (tens of minutes); tests/env/ run the command on small tasks",
}
"""Commands of the README's code blocks that no test can run, and why: keep it short."""

FRAMES = 3
"""Frames a window shows here before the user closes it (8 steps each, at the default speed)."""

SWEEP_CAP = 200
"""Steps a sweep's run may take here (the paper's runs take thousands): a test-only cap."""

SWEEP_RUNS = int(re.search(r"sweeps/strategies.toml +# (\d+) runs", README).group(1))


def blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", README, re.S | re.M)


def commands(block: str) -> list[str]:
    """A shell block's commands, without comments; a transcript's `$ ` lines."""
    lines = block.splitlines()
    if any(line.startswith("$ ") for line in lines):
        lines = [line[2:] for line in lines if line.startswith("$ ")]
    return [re.sub(r"\s+#.*", "", line).strip() for line in lines if line.strip()]


SHELL = [commands(block) for block in blocks("sh") + blocks("text")]


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A user's folder: the shipped shapes and sweeps, a photo, the README's strategy saved as
    it says. A fresh seed is 1, so that a run without --seed repeats; a window closes after
    `FRAMES` frames, as if the user watched that long; a sweep stops its runs at `SWEEP_CAP`."""
    shutil.copytree(ROOT / "shapes", tmp_path / "shapes")
    shutil.copytree(ROOT / "sweeps", tmp_path / "sweeps", ignore=shutil.ignore_patterns("*.csv"))
    sweep = tmp_path / "sweeps" / "strategies.toml"
    sweep.write_text(re.sub(r"^max_steps = .*$", f"max_steps = {SWEEP_CAP}", sweep.read_text(),
                            flags=re.M))  # fmt: skip
    shutil.copy(ROOT / "shapes" / "horse.png", tmp_path / "horse.png")
    Image.open(ROOT / "shapes" / "horse.png").convert("RGB").save(tmp_path / "photo.jpg")
    (tmp_path / "my_strategies.py").write_text(snippet("python", "import numpy as np"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setattr(RunConfig, "seeded", _seed_one)
    monkeypatch.setattr(Viewer, "tick", _closed_after(FRAMES, Viewer.tick))
    return tmp_path


def _seed_one(config: RunConfig) -> RunConfig:
    return config if config.seed is not None else dataclasses.replace(config, seed=1)


def _closed_after(frames: int, tick):
    """`tick` that closes each window after `frames` frames. Counted by the window itself, not
    its id: a new window given a closed one's id started past the count, was never closed,
    and its test ran for good (seen under load; the likely cause of CI's hang at stop 59)."""
    shown: weakref.WeakKeyDictionary[Viewer, int] = weakref.WeakKeyDictionary()

    def tick_then_close(viewer: Viewer) -> bool:
        shown[viewer] = shown.get(viewer, 0) + 1
        if shown[viewer] >= frames:
            pygame.event.post(pygame.event.Event(pygame.QUIT))
        return tick(viewer)

    return tick_then_close


def run(command: str, capsys) -> tuple[int, str, str]:
    """`command` as the shell would run it, in this process: (exit status, stdout, stderr)."""
    words = shlex.split(command)
    if words[0] == "scripts/run":  # its bootstrap is this suite's own (scripts/test)
        words[0] = "swarmshape"
    assert words[0] == "swarmshape", f"the README runs {command!r}: teach this test to run it"
    status = cli.main(words[1:])
    out, err = capsys.readouterr()
    return status, out, err


def test_the_readme_lists_every_run_setting_as_declared():
    found = re.search(r"<!-- settings:[^>]*-->\n(.*?)\n<!-- /settings -->", README, re.S)
    assert found, "the README has no settings table between its markers"
    assert found.group(1) == settings_table()


def test_every_shell_command_of_the_readme_is_run_here_or_said_why_not():
    every = {command for block in SHELL for command in block}
    assert set(NOT_RUNNABLE) <= every, "a command listed as not runnable left the README"
    assert every - set(NOT_RUNNABLE) == set(PROMISES), "a command this test does not run"


def _window(seed=1):
    def check(status, out, err, folder):
        assert status == 0, err
        first, *_, summary = out.splitlines()  # what the user saw when they closed it
        assert first == f"seed {seed}" and re.search(rf", seed {seed}\b", summary)

    return check


def _as_transcribed(status, out, err, folder):
    assert status == 0, err
    assert out.splitlines() == blocks("text")[0].splitlines()[1:]


def _formed_metrics(name):
    def check(status, out, err, folder):
        assert status == 0, err
        assert json.loads((folder / name).read_text())["coverage"] == 1.0

    return check


def _every_strategy(status, out, err, folder):
    assert status == 0, err
    for name in ("optimal", "greedy", "random", "paper", "local-swap", "self-assembly"):
        assert re.search(rf"^{name}\s", out, re.M), name


def _checked(status, out, err, folder):
    assert status == 0, err
    assert "no problems found" in out


def _preview(status, out, err, folder):
    assert status == 0, err
    assert "cells" in out and "#" in out


def _recorded(status, out, err, folder):
    """A GIF, and the same as MP4, of the sizes the README gives (within 5 %: encoders differ
    a little between versions)."""
    assert status == 0, err
    assert Image.open(folder / "star.gif").n_frames > 1
    assert cli.main(["shapes/star.png", "--headless", "--seed", "1", "--record", "star.mp4",
                     "--record-every", "3"]) == 0  # fmt: skip
    sizes = re.search(r"the star above is (\d+) KB as MP4 and (\d+) KB as GIF", README)
    for name, size in zip(("star.mp4", "star.gif"), sizes.groups(), strict=True):
        assert abs((folder / name).stat().st_size / 1000 / int(size) - 1) < 0.05, name


def _traced(status, out, err, folder):
    """The trace's last row equals the metrics file."""
    assert status == 0, err
    metrics = json.loads((folder / "metrics.json").read_text())
    last = list(csv.DictReader((folder / "trace.csv").open()))[-1]
    assert int(last["step"]) == metrics["steps_run"]
    assert float(last["coverage"]) == metrics["coverage"]


def _saved_half_way(status, out, err, folder):
    """Stopped at its cap before forming: exit 3, the state saved."""
    assert status == cli.NOT_FORMED, err
    assert (folder / "half.state").exists()


def _resumed(status, out, err, folder):
    """Goes on exactly where it stopped: formed in the steps of the run never stopped."""
    assert status == 0, err
    whole = configure("shapes/ring.png", seed=1)
    unstopped = _summary(whole)
    assert out.splitlines()[-1].split(": ", 1)[1] == unstopped.split(": ", 1)[1]


def _summary(config: RunConfig) -> str:
    import swarmshape
    from swarmshape.session import summary_line

    swarm = swarmshape.run(swarmshape.build(config), max_steps=config.max_steps)
    return summary_line(swarmshape.run_metrics(swarm))


def _swept(status, out, err, folder):
    assert status == 0, err
    rows = list(csv.DictReader((folder / "sweeps" / "strategies.csv").open()))
    assert len(rows) == SWEEP_RUNS == read_sweep(folder / "sweeps" / "strategies.toml").count


def _plotted(status, out, err, folder):
    assert status == 0, err
    assert {p.name for p in (folder / "plots").iterdir()} == {"coverage.png", "steps.png"}


def _faults_headless(status, out, err, folder):
    assert status == 0, err
    assert "1 fault: 86 robots lost" in out  # a fifth of 430


def _edited(status, out, err, folder):
    assert status == 0, err
    assert not (folder / "mine.png").exists()  # nothing painted, nothing saved


PROMISES = {
    "scripts/run shapes/line.png": _window(),
    "swarmshape horse.png": _window(),
    "swarmshape shapes/two-squares.toml": _window(),
    "swarmshape horse.png --cells 48 --agents 300 --seed 7": _window(7),
    "swarmshape shapes/horseshoe.png --strategy paper": _window(),
    "swarmshape shapes/star.png --headless --metrics star.json": _formed_metrics("star.json"),
    "swarmshape strategies": _every_strategy,
    "swarmshape check my_strategies.py:NearestFirst": _checked,
    "swarmshape photo.jpg --preview": _preview,
    "swarmshape shapes/star.png --headless --seed 1": _as_transcribed,
    "swarmshape edit mine.png": _edited,
    "swarmshape shapes/star.png --headless --seed 1 --record star.gif --record-every 3": _recorded,
    "swarmshape shapes/star.png --headless --trace trace.csv --metrics metrics.json": _traced,
    "swarmshape shapes/ring.png --headless --max-steps 60 --save-state half.state": _saved_half_way,
    "swarmshape --load-state half.state --headless": _resumed,
    "swarmshape sweep sweeps/strategies.toml": _swept,
    "swarmshape plot sweeps/strategies.csv --out plots": _plotted,
    "swarmshape shapes/star.png --agents 430 --fail 0.2@300 --headless": _faults_headless,
    "swarmshape shapes/star.png --fail-region 24,14,8,8@250": _window(),
    "swarmshape shapes/star.png --stall 0.05@200 --failure-rate 0.0001": _window(),
}
"""What each command the README shows must do, checked after it ran."""


@pytest.mark.parametrize("block", range(len(SHELL)), ids=lambda i: SHELL[i][0])
def test_the_commands_of_a_code_block_run_in_turn_as_the_readme_says(block, folder, capsys):
    for command in SHELL[block]:
        if command not in NOT_RUNNABLE:
            PROMISES[command](*run(command, capsys), folder)


SNIPPETS = {
    "python": [
        "import numpy as np",  # the strategy: saved as my_strategies.py and checked
        "from typing import ClassVar",  # the local program: examples/my_program.py
        "import swarmshape",  # the library
        "from swarmshape.env import",  # the learning environment
    ],
    "toml": ['name = "two squares"', "failure_rate = 0.0001"],
}
"""How each snippet of the README begins; each is run or read by a test here."""


def test_every_snippet_of_the_readme_is_run_or_read_here():
    for language, openings in SNIPPETS.items():
        for block in blocks(language):
            assert sum(block.startswith(o) for o in openings) == 1, block.splitlines()[0]
        assert len(blocks(language)) == len(openings)


def snippet(language: str, opening: str) -> str:
    """The README's `language` block that begins with `opening`."""
    return next(block for block in blocks(language) if block.startswith(opening))


def test_the_local_program_shown_is_the_example_a_test_runs():
    assert (
        snippet("python", "from typing import ClassVar")
        in (ROOT / "examples" / "my_program.py").read_text()
    )


def test_the_library_snippet_forms_the_star_in_the_steps_of_the_example_run(folder, capsys):
    exec(snippet("python", "import swarmshape"), {})
    formed_in = re.search(r"formed in (\d+) steps", blocks("text")[0]).group(1)
    assert capsys.readouterr().out == f"{formed_in}\n"


def test_the_learning_snippet_runs_and_observes_what_its_comment_says(folder):
    code = snippet("python", "from swarmshape.env import")
    width, dtype = re.search(r"# \(robots, (\d+)\) (\w+)", code).groups()
    names: dict = {}
    exec(code, names)
    assert names["obs"].shape == (names["vec"].num_envs, int(width))
    assert names["obs"].dtype == dtype
    assert not names["env"].agents  # the episode ran to its end


def test_the_scenario_shown_loads_and_warns_of_the_setting_paper_never_reads(folder, capsys):
    (folder / "shapes" / "shown.toml").write_text(snippet("toml", 'name = "two squares"'))
    status, _, err = run("swarmshape shapes/shown.toml --preview", capsys)
    assert status == 0, err
    assert "msg_loss" in err and "paper" in err
    config = configure("shapes/shown.toml")
    assert (config.seed, config.arena, config.options) == (7, (40, 24), {"order": "outward"})


def test_the_faults_shown_are_read_as_their_comments_say(folder):
    (folder / "shapes" / "faults.toml").write_text(snippet("toml", "failure_rate = 0.0001"))
    config = configure("shapes/faults.toml")
    assert config.failure_rate == 0.0001
    assert [e.values() for e in config.faults] == [
        {"step": 300, "kind": "remove", "amount": 0.2},
        {"step": 600, "kind": "stall", "amount": 10, "region": [24, 14, 8, 8]},
    ]


def test_the_api_reference_builds_without_a_warning_and_covers_the_plugin_api(tmp_path):
    """scripts/docs.py, as the README says; every hook of both plug-in kinds, `Perception`,
    `Blueprint` and every run setting are in it."""
    import swarmshape
    from swarmshape.config import SETTINGS

    assert "scripts/docs.py" in README
    assert script("docs").build(tmp_path) == []
    page = (tmp_path / "swarmshape.html").read_text()
    hooks = [
        f"{kind.__name__}.{name}"
        for kind in (swarmshape.Strategy, swarmshape.Program)
        for name in vars(kind)
        if not name.startswith("_") and callable(getattr(kind, name))
    ]
    assert {"Strategy.on_step", "Strategy.snapshot", "Program.act"} <= set(hooks)
    for name in ["Perception", "Blueprint", "RunConfig", *hooks]:
        assert f'id="{name}"' in page, name
    settings = html.unescape(re.sub(r"<[^>]+>", "", page[page.index('id="RunConfig"') :]))
    for setting in SETTINGS:
        assert f"{setting.name}: {setting.help}" in settings, setting.name


def test_the_letter_k_forms_in_the_steps_the_readme_gives(folder, capsys):
    """The self-assembly paragraph's own command, with the seed the fixture gives."""
    steps, command = re.search(
        r"every seed takes the same ([\d,]+) steps: `([^`]+)`", README
    ).groups()
    status, out, err = run(" ".join(command.split()), capsys)
    assert status == 0, err
    assert f"formed in {steps} steps" in out


def test_the_suite_runs_as_many_examples_a_property_as_the_readme_says():
    from hypothesis import settings

    quick = re.search(r"(\d+) examples a property", README)
    assert quick and settings.get_profile("quick").max_examples == int(quick.group(1))
    assert "a thousand examples each" in README
    whole_runs = re.search(r"(\d+) in all for a property each of whose examples", README)
    assert whole_runs and int(whole_runs.group(1)) == WHOLE_RUN_EXAMPLES
    assert settings.get_profile("slow").max_examples == 1000


def test_the_optimal_disc_forms_in_the_steps_of_the_strategies_and_performance_tables():
    """The 1,000-cell disc is the one benchmark row cheap enough to run here (about a second)."""
    bench = script("bench")
    row = bench.formation(bench.Case("disc", 1000))
    steps, ratio = re.search(r"\| `optimal` \|[^|]*\| ([\d,]+) \(([\d.]+)x", README).groups()
    table = f"| disc | 1,000 | {row['steps_90']} / {row['steps']:,} | {row['bound']} exact | "
    assert (int(steps.replace(",", "")), ratio) == (row["steps"], f"{row['ratio']:.2f}")
    assert table + f"{row['ratio']:.2f}x |" in README


def test_the_shipped_sweeps_hold_the_runs_the_readme_counts():
    def sweep(name: str):
        return read_sweep(ROOT / "sweeps" / f"{name}.toml")

    early = [sweep("early-faults"), sweep("early-stalls")]
    shapes, runs, strategies = re.search(
        r"strike\s+(\w+) shipped shapes while they form \((\d+) runs, all (\w+) strategies",
        README,
    ).groups()
    assert sum(s.count for s in early) == int(runs)
    for each in early:
        assert len(each.values["shape"]) == WORDS[shapes]
        assert len(each.values["strategy"]) == WORDS[strategies]
    noise = sweep("self-assembly-noise")
    assert "all 60 with coverage 1.0" in README and noise.count == 60
    assert "ten seeds each" in README and list(noise.seeds) == list(range(10))
    assert "all 60 runs of the same\nten seeds" in README
    assert sweep("self-assembly-noise-1024").count == 60
    assert "seeds 0 to 2" in README and list(sweep("local-vs-optimal").seeds) == [0, 1, 2]


WORDS = {"three": 3, "eight": 8}


@pytest.mark.parametrize("strategy", ["optimal", "local-swap"])
def test_the_98_robot_letter_s_rows_are_what_the_runs_give(strategy):
    """The local-against-central table's small rows (its 1,018-robot rows take minutes)."""
    import swarmshape

    runs = []
    for seed in (0, 1, 2):
        config = configure(ROOT / "shapes" / "letter-s.png", cells=14, strategy=strategy, seed=seed)
        swarm = swarmshape.run(swarmshape.build(config), max_steps=config.max_steps)
        runs.append(swarmshape.run_metrics(swarm))

    assert {m["agents"] for m in runs} == {98}
    cells = re.search(rf"^\| 98 \| `{strategy}` \|(.*)\|$", README, re.M).group(1).split("|")
    for key, said in zip(COLUMNS, cells, strict=True):
        values = sorted({m[key] for m in runs})
        assert said.strip() == spread(values[0], values[-1], said), key


COLUMNS = ("steps", "makespan_ratio", "distance_ratio", "messages")
"""The columns of the table of local against central runs, after the robots and the strategy."""


def spread(low: float, high: float, said: str) -> str:
    """`low` to `high` (or one value) as `said` prints them: as many decimals, or thousands."""
    decimals = len(said.split()[0].partition(".")[2])
    if decimals:
        low_text, high_text = f"{low:.{decimals}f}", f"{high:.{decimals}f}"
    else:
        step = 1000 if said.split()[0].endswith(",000") else 1
        low_text, high_text = (f"{round(v / step) * step:,}" for v in (low, high))
    return low_text if low_text == high_text else f"{low_text} to {high_text}"

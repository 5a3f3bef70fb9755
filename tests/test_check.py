"""The public checker finds what it promises to find, in plain words."""

from __future__ import annotations

import signal
import sys
import time

import numpy as np
import pytest

from swarmshape.check import StepTooLong, _time_limit, check_strategy, watch_run
from swarmshape.cli import main
from swarmshape.core import compiled
from swarmshape.core.local import QUIET, Program
from swarmshape.core.steering import Strategy
from swarmshape.strategies import available
from swarmshape.strategies.concurrent import Optimal
from tests.conftest import SHAPES, grid_from, world_of


class UsesGlobalRandom(Strategy):
    name = "uses-global-random"
    description = "draws its pairing from numpy's global generator instead of swarm.rng"

    def on_start(self, swarm):
        robots = np.random.permutation(len(swarm.cells))[: len(swarm.targets)]
        swarm.assign(robots, np.arange(len(swarm.targets)))


class NeverStarts(Strategy):
    name = "never-starts"
    description = "hands out nothing"

    def on_start(self, swarm):
        pass


@pytest.mark.parametrize("name", sorted(available()))
def test_every_builtin_strategy_passes(name, request):
    runs = 6 if request.config.getoption("--slow") else 2  # random shapes each
    report = check_strategy(name, runs=runs, seed=1)
    assert report.clean, report.text()


def test_randomness_from_outside_the_run_is_reported():
    report = check_strategy(UsesGlobalRandom, runs=2)
    assert not report.clean
    assert "the same seed gave a different run" in report.problems[0]


def test_a_shape_that_never_forms_is_reported():
    report = check_strategy(NeverStarts, runs=1, max_steps=200)
    assert report.problems[0].endswith("not formed after 200 steps (coverage 0%)")


class StandsStill(Program):
    name = "stands-still"
    description = "never moves: the run comes to rest unformed"

    def act(self, sense, memory, rng):
        return np.zeros(len(sense), dtype=np.int64), np.zeros((len(sense), 0), dtype=np.int64)


def test_a_run_that_ends_unformed_says_when_and_how_unless_it_need_not_form():
    world = world_of(grid_from("###"))
    (problem,) = watch_run(world, StandsStill, 0, max_steps=10 * QUIET).problems
    assert problem == f"ended unformed at step {QUIET}, at rest (coverage 0%)"
    assert watch_run(world, StandsStill, 0, max_steps=10 * QUIET, must_form=False).problems == []
    (problem,) = watch_run(world, StandsStill, 0, max_steps=QUIET // 2, must_form=False).problems
    assert problem == f"not formed after {QUIET // 2} steps (coverage 0%)", "it must end, though"


def test_the_command_reports_and_sets_its_exit_status(capsys):
    assert main(["check", "greedy", "--runs", "2"]) == 0
    assert "no problems found" in capsys.readouterr().out
    assert main(["check", "tests.test_check:NeverStarts", "--runs", "1", "--max-steps", "9"]) == 3
    assert "not formed" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("option", "message"),
    [
        (["--runs", "0"], "--runs must be at least 1, got 0"),
        (["--runs", "-3"], "--runs must be at least 1, got -3"),
        (["--max-steps", "-5"], "--max-steps must be 0 or more, got -5"),
        (["--seed", "-1"], "--seed must be a whole number of 0 or more, got -1"),
    ],
)
def test_numbers_a_check_cannot_use_are_one_clear_line(capsys, option, message):
    """Found by the fuzz: --runs -3 reported '-3 random shapes ... no problems found' (exit
    0), --max-steps -5 'not formed after -5 steps', and --seed -1 was an internal error."""
    assert main(["check", "optimal", "--runs", "1", *option]) == 2
    captured = capsys.readouterr()
    assert captured.err == f"swarmshape: error: {message}\n" and captured.out == ""


class Raises(Optimal):
    name = "raises"

    def on_step(self, swarm):
        if swarm.step == 3:
            raise ValueError("my bug")
        super().on_step(swarm)


class WritesItsView(Optimal):
    name = "writes-its-view"

    def on_step(self, swarm):
        swarm.cells[0] = 5


class WritesItsWorld(Optimal):
    name = "writes-its-world"

    def on_step(self, swarm):
        swarm.world.seeds[:] = 0


class NamesNobody(Optimal):
    name = "names-nobody"

    def on_step(self, swarm):
        swarm.assign(np.array([10**6]), np.array([0]))


class NamesAnotherGroupsTarget(Optimal):
    name = "names-another-groups-target"

    def on_step(self, swarm):
        swarm.send(-1, 0, len(swarm.targets) - 1)


class Exits(Optimal):
    name = "exits"

    def on_step(self, swarm):
        sys.exit(0)


class Loops(Optimal):
    name = "loops"

    def on_step(self, swarm):
        if swarm.step == 2:
            while True:
                pass
        super().on_step(swarm)


class Plain(Optimal):
    name = "plain"
    description = "no code of its own in a step"


FAILURES = [
    ("Raises", "strategy 'raises' failed at step 3: ValueError: my bug (test_check.py, line"),
    ("WritesItsView", "strategy 'writes-its-view' failed as the run started: ValueError: "
     "assignment destination is read-only (test_check.py, line"),
    ("WritesItsWorld", "strategy 'writes-its-world' failed as the run started: ValueError: "
     "assignment destination is read-only (test_check.py, line"),
    ("NamesNobody", "strategy 'names-nobody' failed as the run started: IndexError: assign: there "
     "is no robot 1000000 (they are 0 to"),
    ("NamesAnotherGroupsTarget", "failed as the run started: ValueError: send: target 71 belongs "
     "to group 1 and robot 0 to group 0 (test_check.py, line"),
    ("Exits", "strategy 'exits' called sys.exit(0) as the run started (test_check.py, line"),
]  # fmt: skip


@pytest.mark.parametrize(("name", "message"), FAILURES, ids=[f[0] for f in FAILURES])
def test_a_failure_of_a_strategys_own_code_is_one_line_naming_it(capsys, name, message):
    """Issue 29, case 9: a user strategy that raised, wrote to its view or named a robot that
    does not exist was "internal error, please report it" (exit 1); sys.exit(0) ended the run
    without a word."""
    shape = str(SHAPES / ("two-squares.toml" if "Groups" in name else "line.png"))
    assert main([shape, "--headless", "--strategy", f"tests.test_check:{name}"]) == 2
    err = [line for line in capsys.readouterr().err.splitlines() if " warning: " not in line]
    assert len(err) == 1 and err[0].startswith("swarmshape: error: "), err
    assert message in err[0], err[0]


@pytest.mark.parametrize(("name", "message"), FAILURES[:1] + FAILURES[-1:], ids=["raises", "exits"])
def test_check_reports_a_strategys_failure_in_plain_words(capsys, name, message):
    assert main(["check", f"tests.test_check:{name}", "--runs", "3"]) == 3
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith("3 random shapes, each run twice: 1 problem"), out
    assert out[1].startswith("  - shape 0 (") and message in out[1], out


def test_check_stops_a_step_that_never_ends():
    """Issue 29, case 9: a strategy that looped hung the check for ever."""
    # the limit leaves room for a start that compiles the kernels on a loaded machine (0.3 s
    # did not, under a load of 8 on 2 cores); the loop is caught at step 2 all the same
    report = check_strategy(Loops, runs=2, step_seconds=3.0)
    assert len(report.problems) == 1
    assert report.problems[0].endswith(
        "step 2 took over 3 s (is the strategy caught in a loop?); the check stopped it"
    )


def _plus_one(x: int) -> int:
    return x + 1


def test_a_kernel_compiling_in_a_step_is_not_taken_for_a_loop(monkeypatch):
    """A cold numba cache compiles the project's kernels in a run's first steps, for seconds on
    a loaded machine: the limit on a step stopped it inside numba, which broke it (a traceback
    from scripts/fuzz_programs.py --step-seconds 1 in a fresh clone), and then stopped a step
    whose own work, after the compiling, was well within it."""
    import numba

    def slow_njit(**_: object):
        def compile_kernel(python):
            time.sleep(1.2)  # past two ticks of the limit's timer
            return python

        return compile_kernel

    monkeypatch.setattr(numba, "njit", slow_njit)
    kernel = compiled.njit(_plus_one)

    def compiles_then_works() -> int:
        value = kernel(1)
        time.sleep(0.35)  # across the next tick, within the limit of its own
        return value

    with _time_limit(0.5) as limited:
        assert limited(compiles_then_works) == 2
        with pytest.raises(StepTooLong):
            limited(lambda: time.sleep(1.0))


def test_a_tick_handled_after_the_call_leaves_no_timer_behind():
    """A tick of the limit's timer can be handled just after its call ended. It set the timer
    again, and where that came between the limit's last clearing of the timer and its giving
    the signal back, the signal's default action ended the process later (a test worker, say,
    whose run then waited for it for good)."""
    with _time_limit(5.0) as limited:
        limited(lambda: None)
        signal.raise_signal(signal.SIGALRM)  # the tick, handled late
        assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)


def test_code_that_fails_as_it_loads_is_its_own_failure(tmp_path, capsys):
    (tmp_path / "broken.py").write_text("raise RuntimeError('import boom')\n")
    (tmp_path / "made.py").write_text(
        "from swarmshape.strategies.concurrent import Optimal\n"
        "class Made(Optimal):\n    name = 'made'\n"
        "    def __init__(self, options=None):\n        1 / 0\n"
    )
    for spec, where in ((f"{tmp_path / 'broken.py'}:X", "broken.py, line 1"),
                        (f"{tmp_path / 'made.py'}:Made", "made.py, line 5")):  # fmt: skip
        for command in ([str(SHAPES / "line.png"), "--headless", "--strategy", spec],
                        ["check", spec, "--runs", "1"]):  # fmt: skip
            code = main(command)
            captured = capsys.readouterr()
            said = captured.err if code == 2 else captured.out
            assert code == (3 if command[0] == "check" and "made" in spec else 2), said
            assert "failed as it" in said and where in said, said


def test_a_bug_of_ours_under_a_users_strategy_stays_ours(monkeypatch, capsys):
    from swarmshape import check
    from swarmshape.core.steering import Steering

    monkeypatch.setattr(Steering, "_who_moves", check.random_world)  # fails inside swarmshape
    argv = [str(SHAPES / "line.png"), "--headless", "--strategy", "tests.test_check:Plain"]
    assert main(argv) == 1
    assert "internal error, please report it" in capsys.readouterr().err


class Plans(Optimal):
    """Keeps what any planner keeps, set up in on_start: a list of numpy integers, a count."""

    name = "plans"

    def on_start(self, swarm):
        self.order = list(np.argsort(swarm.targets[:, 0]))
        self.steps = 0
        super().on_start(swarm)

    def on_step(self, swarm):
        self.steps += 1
        assert len(self.order) == len(swarm.targets)
        super().on_step(swarm)


class KeepsATable(Plans):
    name = "keeps-a-table"

    def on_start(self, swarm):
        self.table = {"a": 1}
        super().on_start(swarm)


def test_what_a_strategy_sets_up_in_on_start_is_saved_and_resumed(tmp_path, capsys):
    """Issue 29, case 16: a strategy that kept state set in on_start saved, passed check, and
    crashed on --load-state (the attribute did not exist after __init__); a list of numpy
    integers was refused as "not numbers", and only after the whole run."""
    common = [str(SHAPES / "line.png"), "--headless", "--seed", "4", "--strategy",
              "tests.test_check:Plans"]  # fmt: skip
    assert main([*common, "--metrics", str(tmp_path / "whole.json")]) == 0
    assert main([*common, "--max-steps", "6", "--save-state", str(tmp_path / "s.state")]) == 3
    resumed = ["--load-state", str(tmp_path / "s.state"), "--headless", "--strategy",
               "tests.test_check:Plans", "--metrics", str(tmp_path / "resumed.json")]  # fmt: skip
    assert main(resumed) == 0
    assert (tmp_path / "whole.json").read_text() == (tmp_path / "resumed.json").read_text()
    assert check_strategy(Plans, runs=2).clean


def test_a_strategy_that_keeps_what_a_state_cannot_hold_is_told_before_the_run(tmp_path, capsys):
    argv = [str(SHAPES / "line.png"), "--headless", "--strategy", "tests.test_check:KeepsATable",
            "--save-state", str(tmp_path / "s.state")]  # fmt: skip
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and list(tmp_path.iterdir()) == []
    assert captured.err == (
        f"swarmshape: error: {tmp_path / 's.state'}: --save-state cannot save this run: strategy "
        "'keeps-a-table' keeps a dict in self.table, which a state file cannot hold: keep numbers, "
        "text and numpy arrays (or lists of them), or define snapshot() and restore()\n"
    )
    report = check_strategy(KeepsATable, runs=2)
    assert report.problems[0].endswith(
        "step 5: the run could not be saved and resumed: strategy 'keeps-a-table' keeps a dict "
        "in self.table, which a state file cannot hold: keep numbers, text and numpy arrays (or "
        "lists of them), or define snapshot() and restore()"
    )


class TakesNoOptions(Optimal):
    name = "takes-no-options"

    def __init__(self):
        super().__init__()


def test_a_constructor_without_options_is_refused_in_one_line(capsys):
    """Issue 29: a strategy whose __init__ took no options failed inside swarmshape's call of
    it: "internal error, please report it"."""
    spec = "tests.test_check:TakesNoOptions"
    for command in ([str(SHAPES / "line.png"), "--headless", "--strategy", spec],
                    ["check", spec, "--runs", "1"]):  # fmt: skip
        assert main(command) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and "its __init__ must take its options" in err[0], err

"""The public checker finds what it promises to find, in plain words."""

from __future__ import annotations

import numpy as np
import pytest

from swarmshape.check import check_strategy
from swarmshape.cli import main
from swarmshape.core.steering import Strategy
from swarmshape.strategies import available


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
def test_every_builtin_strategy_passes(name):
    report = check_strategy(name, runs=3 if name == "paper" else 6, seed=1)
    assert report.clean, report.text()


def test_randomness_from_outside_the_run_is_reported():
    report = check_strategy(UsesGlobalRandom, runs=2)
    assert not report.clean
    assert "the same seed gave a different run" in report.problems[0]


def test_a_shape_that_never_forms_is_reported():
    report = check_strategy(NeverStarts, runs=1, max_steps=200)
    assert report.problems[0].endswith("not formed after 200 steps (coverage 0%)")


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

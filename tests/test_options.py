"""One table of settings: declared once, checked the same way from every door (code, files, the
command line, a saved run, a sweep), and a plug-in's own options beside them."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

from swarmshape.cli import main
from swarmshape.config import SETTINGS, RunConfig, configure, plugin_options
from swarmshape.core.options import option, specs
from swarmshape.errors import SettingError, SettingWarning
from swarmshape.experiments.results import read_rows
from swarmshape.experiments.sweep import read_sweep, sweep
from swarmshape.runs import build, resume, run, save
from tests.conftest import SHAPES


@dataclass(frozen=True)
class Knobs:
    reach: int = option(8, "hops", at_least=1, at_most=64)
    share: float = option(0.5, "a fraction", at_least=0.0, below=1.0)
    loud: bool = False
    mode: str = option("a", "a mode", choices=("a", "b"))


@pytest.mark.parametrize(
    ("name", "value", "problem"),
    [
        ("reach", 0, "must be a whole number from 1 to 64, got 0"),
        ("reach", 2.0, "must be a whole number from 1 to 64, got 2.0"),
        ("reach", True, "must be a whole number from 1 to 64, got True"),
        ("share", math.nan, "must be a number from 0 up to (not including) 1, got nan"),
        ("share", math.inf, "must be a number from 0 up to (not including) 1, got inf"),
        ("share", 1, "must be a number from 0 up to (not including) 1, got 1.0"),
        ("share", "0.3", "must be a number from 0 up to (not including) 1, got '0.3'"),
        ("loud", 1, "must be true or false, got 1"),
        ("mode", "c", "must be one of a, b, got 'c'"),
    ],
)
def test_a_value_of_the_wrong_kind_or_out_of_range_names_its_setting(name, value, problem):
    spec = next(spec for spec in specs(Knobs) if spec.name == name)
    with pytest.raises(SettingError) as error:
        spec.check(value)
    assert (error.value.setting, error.value.problem) == (name, problem)


def test_plain_values_are_coerced_to_their_kind():
    reach, share, loud, _ = specs(Knobs)
    assert reach.check(np.int64(12)) == 12 and type(reach.check(np.int64(12))) is int
    assert share.check(0) == 0.0 and type(share.check(0)) is float
    assert loud.check(np.bool_(True)) is True


@pytest.mark.parametrize(
    ("name", "text", "value"),
    [("reach", "12", 12), ("share", "0.25", 0.25), ("loud", "yes", True), ("loud", "off", False)],
)
def test_text_from_a_command_line_is_read_by_the_kind(name, text, value):
    spec = next(spec for spec in specs(Knobs) if spec.name == name)
    assert spec.parse(text) == value


@pytest.mark.parametrize("text", ["²", "٣", "1e3", "twelve", ""])
def test_text_that_is_not_a_whole_number_is_refused(text):
    with pytest.raises(SettingError, match="must be a whole number"):
        specs(Knobs)[0].parse(text)


def test_every_run_setting_is_named_as_its_field_and_has_help():
    fields = list(RunConfig.__dataclass_fields__)
    assert [spec.name for spec in SETTINGS] == fields
    assert all(spec.help for spec in SETTINGS)


def test_a_saved_description_round_trips_through_plain_values():
    with pytest.warns(SettingWarning, match="msg_loss is read only by local plug-ins"):
        config = configure(SHAPES / "two-squares.toml", seed=3, arena=(50, 40), msg_loss=0.1)
    plain = json.loads(json.dumps(config.values()))
    assert RunConfig.from_values(plain, "saved") == config


def test_an_unknown_setting_and_a_plug_in_option_given_as_a_setting_say_what_to_do():
    with pytest.raises(SettingError, match="speed is not a run setting; the run settings are"):
        configure(SHAPES / "square.png", speed=3)
    with pytest.raises(SettingError, match="order is an option of paper, not a run setting"):
        configure(SHAPES / "square.png", order="random")


def test_a_setting_the_plug_in_never_reads_is_a_warning():
    with pytest.warns(SettingWarning, match="msg_loss is read only by local plug-ins"):
        configure(SHAPES / "square.png", strategy="optimal", msg_loss=0.2)


def test_options_reach_the_plug_in_and_are_kept_by_a_saved_run(tmp_path):
    config = configure(
        SHAPES / "small-square.png", strategy="paper", seed=2, options={"order": "random"}
    )
    assert plugin_options(config).order == "random"
    half = run(build(config), max_steps=40)
    save(half, tmp_path / "half.state", config)
    saved, swarm = resume(tmp_path / "half.state")
    assert saved.options == {"order": "random"} and swarm.plugin.options.order == "random"
    whole = run(build(config))
    run(swarm)
    assert np.array_equal(whole.cell, swarm.cell) and whole.step_count == swarm.step_count


def test_the_file_options_of_another_strategy_are_dropped_with_a_word():
    with pytest.warns(SettingWarning, match="order in .*two-squares.toml is for paper: ignored"):
        config = configure(SHAPES / "two-squares.toml", strategy="optimal")
    assert config.options == {}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--strategy", "paper", "--set", "order=inward"], "order must be one of outward"),
        (["--strategy", "paper", "--set", "oder=random"], "oder is not an option of paper"),
        (["--set", "order=random"], "order is an option of paper, not of optimal"),
        (["--strategy", "self-assembly", "--set", "alone=nan"], "alone must be a whole number"),
        (["--strategy", "self-assembly", "--set", "alone=-1"], "alone must be a whole number of 0"),
        (["--strategy", "self-assembly", "--set", "alone=1.5"], "alone must be a whole number"),
        (["--set", "order"], "expected NAME=VALUE"),
        (["--order", "random"], "--order is an option of paper: give it as --set order=VALUE"),
        (["--max-speed", "nan"], "--max-speed: must be a number from 0.001 to 1, got 'nan'"),
        # past 64 bits, numpy refused it mid-run: an internal error (`options.LARGEST`)
        (["--strategy", "self-assembly", "--set", f"patience={2**64}"], "at most 9,223,372,"),
        (["--strategy", "mean-shift", "--set", "lap_pace=1e18"], "lap_pace must be a number f"),
    ],
)
def test_bad_options_on_the_command_line_are_one_line_and_exit_2(capsys, args, message):
    try:
        code = main([str(SHAPES / "square.png"), "--headless", "--max-steps", "1", *args])
    except SystemExit as stop:  # the argument grammar's own errors
        code = stop.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("swarmshape: error: ") and message in err[0]


def test_a_sweep_over_an_option_runs_each_value_and_resumes(tmp_path):
    (tmp_path / "s.toml").write_text(
        f"shapes = ['{SHAPES / 'small-square.png'}']\nstrategies = ['paper']\nseeds = 1\n"
        "options.order = ['outward', 'random']\nmax_steps = 20\n"
    )
    runs = read_sweep(tmp_path / "s.toml")
    assert sorted(r["options.order"] for r in runs) == ["outward", "random"]
    out = tmp_path / "s.csv"
    assert sweep(runs, out, tmp_path, workers=1) == 2
    rows = read_rows(out)
    assert sorted(row["config.options.order"] for row in rows) == ["outward", "random"]
    assert sweep(runs, out, tmp_path, workers=1) == 0  # both there already


def test_strategies_name_lists_its_options(capsys):
    assert main(["strategies", "self-assembly"]) == 0
    text = capsys.readouterr().out
    assert "lossy_patience  a whole number of 1 or more, default 8" in text
    assert "does not read" not in text
    assert main(["strategies", "paper"]) == 0
    assert "does not read the run settings sense_radius" in capsys.readouterr().out

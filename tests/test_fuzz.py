"""Nothing a user does loses their work or surprises them: a property-based fuzz of the
command line and of mutated images, scenarios, start cells, state files, sweep files and
sweep results. Every case ends in exit status 0, 2 or 3 with at most one error line (and one
warning), no traceback, and no file changed that the command line did not name as an output
(`tests.fuzzing` has the cases and the rules; ``scripts/fuzz.py`` runs thousands).

Cases run in this process, which is fast; those that read a pipe or a device run in a forked
process with their memory and time limited. ``pytest --slow`` runs twenty times as many.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests import fuzzing


class Data:
    """`fuzzing.Pick` over hypothesis' data, so that failing cases shrink."""

    def __init__(self, data: st.DataObject) -> None:
        self.data = data

    def integer(self, low: int, high: int) -> int:
        return self.data.draw(st.integers(low, high))

    def choice(self, options):
        return self.data.draw(st.sampled_from(options))


@pytest.fixture(scope="module")
def material(tmp_path_factory) -> Path:
    return fuzzing.make_material(tmp_path_factory.mktemp("material"))


def examples(share: int) -> settings:
    """`share` % of the profile's examples (50 by default, 1000 with --slow)."""
    return settings(
        max_examples=max(1, settings().max_examples * share // 100),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


def holds(material: Path, data: st.DataObject, kind: str, *, isolated: bool = False) -> None:
    """Draw a case of `kind`, run it, and fail with its problems and how to run it again."""
    base = Path(tempfile.mkdtemp(prefix="fuzz-"))
    try:
        case = fuzzing.make_case(Data(data), kind, material, base / "case", isolated)
        runner = fuzzing.run_forked if case.isolated else fuzzing.run_here
        outcome, problems = fuzzing.attempt(case, runner)
        where = fuzzing.crash(outcome)
        assert not problems, (
            f"{'; '.join(problems)}\n{case.command()}\nexit status {outcome.status}\n"
            f"stderr: {outcome.stderr}" + (f"crash: {where[1]} in {where[0]}" if where else "")
        )
    finally:
        shutil.rmtree(base, ignore_errors=True)


def test_the_rules_catch_what_they_promise(tmp_path):
    """The fuzz is only as good as its rules: each kind of misstep is named."""
    (tmp_path / "notes.txt").write_text("the user's")
    case = fuzzing.Case("command line", ["shape.png", "--metrics", "m.json"], tmp_path, False)
    named, before = fuzzing.Named(case), fuzzing.snapshot(tmp_path)
    (tmp_path / "m.json").write_text("{}")
    assert (
        fuzzing.problems(named, fuzzing.Outcome(0, "", "", 0), before, fuzzing.snapshot(tmp_path))
        == []
    )
    (tmp_path / "notes.txt").write_text("changed")
    (tmp_path / ".swarmshape-x1y2.json").write_text("")
    stderr = "Traceback (most recent call last):\nswarmshape: error: a\nswarmshape: error: b\n"
    outcome = fuzzing.Outcome(1, "", stderr, 0)
    found = fuzzing.problems(named, outcome, before, fuzzing.snapshot(tmp_path))
    assert found == [
        "exit status 1",
        "a traceback or an internal error",
        "3 lines on stderr",
        "changed what it was not asked to: .swarmshape-x1y2.json",
        "left a temporary file: .swarmshape-x1y2.json",
    ]
    refused = fuzzing.Outcome(2, "", "swarmshape: error: no\n", 0)
    found = fuzzing.problems(named, refused, before, fuzzing.snapshot(tmp_path))
    assert "refused, yet left .swarmshape-x1y2.json behind" in found
    assert fuzzing.problems(named, fuzzing.Outcome(None, "", "", 120), before, before) == [
        "did not finish in 120 s"
    ]


def test_an_input_named_as_an_output_may_still_not_change(tmp_path):
    """Issue 29, case 1: an output over a file the run reads is a loss even with --force."""
    (tmp_path / "shape.png").write_text("the user's picture")
    argv = ["shape.png", "--metrics", "shape.png", "--force"]
    named = fuzzing.Named(fuzzing.Case("command line", argv, tmp_path, False))
    before = fuzzing.snapshot(tmp_path)
    (tmp_path / "shape.png").write_text("{}")
    found = fuzzing.problems(named, fuzzing.Outcome(2, "", "swarmshape: error: x\n", 0), before,
                             fuzzing.snapshot(tmp_path))  # fmt: skip
    assert found == ["changed what it was not asked to: shape.png"]
    resumed = ["--load-state", "s.state", "--save-state", "s.state"]
    assert fuzzing.Named(fuzzing.Case("state file", resumed, tmp_path, False)).allows("s.state")


@examples(50)
@given(data=st.data())
def test_command_lines(material, data):
    holds(material, data, "command line")


@examples(40)
@given(data=st.data())
def test_mutated_images(material, data):
    holds(material, data, "image")


@examples(25)
@given(data=st.data())
def test_mutated_scenarios(material, data):
    holds(material, data, "scenario")


@examples(15)
@given(data=st.data())
def test_mutated_start_cells(material, data):
    holds(material, data, "start cells")


@examples(40)
@given(data=st.data())
def test_mutated_state_files(material, data):
    holds(material, data, "state file")


@examples(10)
@given(data=st.data())
def test_mutated_sweep_files(material, data):
    holds(material, data, "sweep file")


@examples(15)
@given(data=st.data())
def test_mutated_sweep_results(material, data):
    holds(material, data, "sweep results")


@examples(15)
@given(data=st.data())
def test_pipes_and_devices_are_refused_not_read(material, data):
    holds(material, data, "pipe or device", isolated=True)


@examples(8)
@given(data=st.data())
def test_runs_cut_short_by_a_full_disk_or_a_signal_leave_whole_files_only(material, data):
    holds(material, data, "full disk or signal", isolated=True)


@pytest.mark.parametrize("crash", fuzzing.FOUND, ids=lambda found: f"{found.where} {found.error}")
def test_crashes_the_fuzz_found_stay_fixed(material, tmp_path, crash):
    """Each crash the fuzz once found is now one clear line (a regression test per crash)."""
    folder = tmp_path / "case"
    shutil.copytree(material, folder)
    if crash.state is not None:
        state = fuzzing.changed_state(folder / "paper.state", crash.state)
        (folder / "fuzz.state").write_bytes(state)
    case = fuzzing.Case("found", list(crash.argv), folder, False)
    outcome, problems = fuzzing.attempt(case, fuzzing.run_here)
    assert fuzzing.crash(outcome) is None, "it crashes again"
    assert not problems, outcome.stderr

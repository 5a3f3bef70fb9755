"""Saved runs: resuming is exact for every strategy, and a state file never runs code, never
loads damaged, and never hangs on something that is not a file."""

from __future__ import annotations

import functools
import itertools
import json
import os
import pickle
import re
import threading
import zipfile

import numpy as np
import pytest

from swarmshape.cli import main
from swarmshape.config import configure
from swarmshape.core.faults import LOG_KEYS
from swarmshape.core.metrics import run_metrics
from swarmshape.errors import InputError
from swarmshape.io.checkpoint import PICKLE_HEADER, load_state
from swarmshape.runs import build, resume, run, save
from swarmshape.strategies import available
from swarmshape.strategies.local_swap import LocalSwap
from tests.conftest import SHAPES, each_choice
from tests.fuzzing import changed_state, state_bytes, state_members


def config_for(strategy: str):
    return configure(SHAPES / "horseshoe.png", cells=12, seed=5, strategy=strategy, agents=60)


def metrics_of(swarm) -> str:
    return json.dumps(run_metrics(swarm), sort_keys=True)


@functools.cache
def uninterrupted(strategy: str) -> str:
    """The metrics of `config_for(strategy)` run to its end without a stop."""
    return metrics_of(run(build(config_for(strategy)), max_steps=50_000))


@pytest.mark.parametrize(  # a strategy left over by the covering cases gets the latest cut
    ("strategy", "cut"), each_choice(itertools.product(sorted(available()), [150, 23, 1, 0]))
)
def test_resuming_at_any_step_gives_the_uninterrupted_run(strategy, cut, tmp_path):
    config = config_for(strategy)
    save(run(build(config), max_steps=cut), tmp_path / "s.state", config)
    again, resumed = resume(tmp_path / "s.state")
    assert again == config
    assert metrics_of(run(resumed, max_steps=50_000)) == uninterrupted(strategy)


def test_a_run_saved_before_its_program_kept_a_memory_slot_resumes_with_it_as_new(tmp_path):
    """A state file of an older version lacks the slots a program added since (`mean-shift`'s
    `walled`): each starts as a new robot's, and the run goes on as it would have."""
    config = config_for("mean-shift")
    save(run(build(config), max_steps=23), tmp_path / "s.state", config)
    manifest, arrays = state_members(tmp_path / "s.state")
    del arrays["swarm.driver.memory.walled"]
    (tmp_path / "old.state").write_bytes(state_bytes(manifest, arrays))
    _, resumed = resume(tmp_path / "old.state")
    assert metrics_of(run(resumed, max_steps=50_000)) == uninterrupted("mean-shift")
    del arrays["swarm.driver.memory.frame"]  # a slot it always kept: the file is damaged
    (tmp_path / "old.state").write_bytes(state_bytes(manifest, arrays))
    with pytest.raises(InputError, match=re.escape("memory.frame is missing")):
        resume(tmp_path / "old.state")


def test_a_run_saved_before_its_program_broadcast_a_field_resumes_with_it_as_0(tmp_path):
    """`local-swap` appended the message fields OPEN_AGE, SPARE_HOPS, SPARE_AGE and MOVING
    (and four memory slots) after runs were saved: a file without them resumes, the fields as
    0 and the slots as new, and the run forms (not step for step as it would have: for a step,
    every robot's news reads as just heard, every robot as one without a goal, and none as
    under way). A broadcast wider than the program's is damaged."""
    config = config_for("local-swap")
    save(run(build(config), max_steps=23), tmp_path / "s.state", config)
    manifest, arrays = state_members(tmp_path / "s.state")
    for slot in ("heard_at", "spare_hops", "spare_at", "spare_until"):
        del arrays[f"swarm.driver.memory.{slot}"]
    broadcast = arrays["swarm.driver.broadcast"]
    arrays["swarm.driver.broadcast"] = broadcast[:, :-4].copy()
    (tmp_path / "old.state").write_bytes(state_bytes(manifest, arrays))
    _, resumed = resume(tmp_path / "old.state")
    formed = run(resumed, max_steps=50_000)
    assert formed.complete
    assert formed.overlap_total == 0
    arrays["swarm.driver.broadcast"] = np.pad(broadcast, ((0, 0), (0, 1)))
    (tmp_path / "wide.state").write_bytes(state_bytes(manifest, arrays))
    width = LocalSwap.message_size
    with pytest.raises(InputError, match=f"broadcast has {width + 1} fields, expected {width}"):
        resume(tmp_path / "wide.state")


def test_the_paper_horseshoe_resumed_at_step_37_forms_as_if_never_stopped(tmp_path):
    """The reported case: the resumed run used to hold two copies of the occupancy grid."""
    common = [str(SHAPES / "horseshoe.png"), "--strategy", "paper", "--seed", "11", "--headless"]
    assert main([*common, "--metrics", str(tmp_path / "whole.json")]) == 0
    assert main([*common, "--max-steps", "37", "--save-state", str(tmp_path / "h.state")]) == 3
    assert main(["--load-state", str(tmp_path / "h.state"), "--headless", "--metrics",
                 str(tmp_path / "resumed.json")]) == 0  # fmt: skip
    whole, resumed = (
        json.loads((tmp_path / f"{n}.json").read_text()) for n in ("whole", "resumed")
    )
    assert resumed == whole and resumed["coverage"] == 1.0


def test_a_pickle_state_file_is_refused_without_being_unpickled(tmp_path):
    witness = tmp_path / "ran"

    class Exploit:
        def __reduce__(self):
            return (open, (str(witness), "w"))

    path = tmp_path / "old.state"
    path.write_bytes(PICKLE_HEADER + pickle.dumps(Exploit()))
    with pytest.raises(InputError, match="older swarmshape"):
        load_state(path)
    assert not witness.exists()


def saved_state(tmp_path):
    config = config_for("optimal")
    path = tmp_path / "s.state"
    save(run(build(config), max_steps=20), path, config)
    return path, config


def test_every_flipped_byte_is_refused_or_changes_nothing(tmp_path):
    path, _ = saved_state(tmp_path)
    expected = metrics_of(run(resume(path)[1], max_steps=50_000))
    original = path.read_bytes()
    rng = np.random.default_rng(0)
    refused = 0
    for position in rng.choice(len(original), 60, replace=False):
        damaged = bytearray(original)
        damaged[position] ^= 1 << int(rng.integers(8))
        path.write_bytes(bytes(damaged))
        try:
            _, swarm = resume(path)
        except InputError as error:
            assert "\n" not in str(error)
            refused += 1
            continue
        assert metrics_of(run(swarm, max_steps=50_000)) == expected, f"byte {position}"
    assert refused > 40, "flips in the data must be caught"


def test_a_changed_value_fails_the_checksum(tmp_path):
    path, _ = saved_state(tmp_path)
    with np.load(path, allow_pickle=False) as stored:
        members = {name: stored[name] for name in stored.files}
    manifest = json.loads(members.pop("manifest").tobytes())
    manifest["values"]["swarm.step"] += 1
    text = json.dumps(manifest).encode()
    with path.open("wb") as handle:  # np.savez would add .npz to a name
        np.savez(handle, manifest=np.frombuffer(text, np.uint8), **members)
    with pytest.raises(InputError, match="checksum does not match"):
        load_state(path)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "not a swarmshape state file"),
        (b"PK\x03\x04garbage", "not a swarmshape state file"),
        (b"hello, world", "not a swarmshape state file"),
    ],
)
def test_foreign_files_are_refused_in_one_line(tmp_path, content, message):
    path = tmp_path / "x.state"
    path.write_bytes(content)
    with pytest.raises(InputError, match=message):
        load_state(path)


def test_a_npz_of_someone_else_is_not_a_state(tmp_path):
    path = tmp_path / "data.npz"
    np.savez(path, values=np.arange(3))
    with pytest.raises(InputError, match="not a swarmshape state file"):
        load_state(path)


def test_a_fifo_is_refused_at_once_instead_of_hanging(tmp_path):
    fifo = tmp_path / "pipe.state"
    os.mkfifo(fifo)
    outcome = []
    thread = threading.Thread(target=lambda: outcome.append(_refusal(fifo)), daemon=True)
    thread.start()
    thread.join(5)
    assert outcome and "not a regular file" in outcome[0]


def _refusal(path) -> str:
    try:
        load_state(path)
    except InputError as error:
        return str(error)
    return "loaded"


def test_a_run_saved_with_code_resumes_only_when_that_code_is_named_again(tmp_path):
    strategy_file = tmp_path / "mine.py"
    strategy_file.write_text(
        "from swarmshape.strategies.concurrent import Optimal\n"
        "class Mine(Optimal):\n    name = 'mine'\n"
    )
    spec = f"{strategy_file}:Mine"
    state = tmp_path / "s.state"
    common = [str(SHAPES / "line.png"), "--headless", "--seed", "2"]
    assert main([*common, "--strategy", spec, "--max-steps", "5", "--save-state", str(state)]) == 3
    with pytest.raises(InputError, match="which is code"):
        resume(state)
    with pytest.raises(InputError, match="cannot change it"):
        resume(state, "optimal")
    config, swarm = resume(state, spec)
    assert config.strategy == spec and type(swarm.plugin).__name__ == "Mine"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--seed", "3"], "--seed cannot change it"),
        (["--agents", "9"], "--agents cannot change it"),
        (["--stall", "0.1@5"], "--fail, --stall or --fail-region cannot change it"),  # no --faults
        ([str(SHAPES / "star.png")], "would not be used"),
    ],
)
def test_options_a_resume_would_ignore_are_refused(tmp_path, capsys, extra, message):
    state = tmp_path / "s.state"
    assert main([str(SHAPES / "line.png"), "--headless", "--max-steps", "3", "--save-state",
                 str(state)]) == 3  # fmt: skip
    assert main(["--load-state", str(state), "--headless", *extra]) == 2
    assert message in capsys.readouterr().err


def rewritten(path, edit) -> None:
    """The state file at `path` with its manifest's text changed by `edit`."""
    with np.load(path, allow_pickle=False) as stored:
        members = {name: stored[name] for name in stored.files}
    text = edit(members.pop("manifest").tobytes().decode())
    with path.open("wb") as handle:
        np.savez(handle, manifest=np.frombuffer(text.encode(), np.uint8), **members)


@pytest.mark.parametrize(
    "edit",
    [
        lambda text: text.replace('"swarm.step": 20', '"swarm.step": NaN'),
        lambda text: text.replace('"swarm.step": 20', '"swarm.step": -Infinity'),
        lambda text: text.replace('"swarm.step": 20', '"swarm.step": 1e400'),
        lambda text: text.replace('"swarm.step": 20', f'"swarm.step": {"[" * 5000}{"]" * 5000}'),
    ],
    ids=["nan", "infinity", "overflowing", "nested"],
)
def test_a_manifest_json_cannot_hold_is_a_damaged_state(tmp_path, edit):
    """Found by the fuzz: NaN or 1e400 in the manifest crashed the checksum (allow_nan=False),
    and nesting 5,000 deep crashed the JSON reader; each was an internal error."""
    path, _ = saved_state(tmp_path)
    rewritten(path, edit)
    with pytest.raises(InputError, match="damaged state file"):
        load_state(path)


def with_array_header(path, edit) -> None:
    """The state file at `path` with the header of its ``swarm.cell`` array changed by `edit`
    (its padding keeps its length), and every checksum left as it was."""
    with zipfile.ZipFile(path) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    npy = members["swarm.cell.npy"]
    end = npy.index(b"\n")
    header = edit(npy[:end].decode("latin-1")).rstrip(" ").ljust(end).encode("latin-1")
    members["swarm.cell.npy"] = header + npy[end:]
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)


@pytest.mark.parametrize(
    "edit",
    [
        lambda header: header.replace("}", "} (", 1),
        lambda header: re.sub(r"'shape': \(\d+,", "'shape': (1000000000000,", header),
    ],
    ids=["unclosed bracket", "huge declared shape"],
)
def test_a_damaged_array_header_is_a_damaged_state(tmp_path, edit):
    """Found by test_every_flipped_byte_is_refused_or_changes_nothing in a checkout whose
    path made the file a few bytes longer: numpy's TokenError on a header with an unclosed
    bracket, and its MemoryError on a header declaring 10**12 robots, were internal errors."""
    path, _ = saved_state(tmp_path)
    with_array_header(path, edit)
    with pytest.raises(InputError, match="damaged state file"):
        load_state(path)


@pytest.mark.parametrize("member", ["manifest.npy", "swarm.cell.npy"])
def test_a_member_of_raw_bytes_is_a_damaged_state(tmp_path, member):
    """Issue 29, case 12: a member that is not a .npy array (numpy hands it over as bytes) was
    an AttributeError when it was the manifest."""
    path, _ = saved_state(tmp_path)
    with zipfile.ZipFile(path) as archive:
        members = {info.filename: archive.read(info) for info in archive.infolist()}
    members[member] = members["manifest.npy"][members["manifest.npy"].index(b"{") :]
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    with pytest.raises(InputError, match="damaged state file"):
        load_state(path)


CRAFTED = {
    "overlaps counted": (lambda m: {"swarm.overlap_total": 136}, "overlap_total is 136"),
    "a step beyond any count": (lambda m: {"swarm.step": 10**100}, "swarm.step is 1000"),
    "completed after the step": (lambda m: {"swarm.completed_at": [10**6]}, "completed_at holds"),
    "plans of another length": (
        lambda m: {"swarm.driver.strategy._planned": np.zeros(3, dtype=np.int64)},
        "_planned does not hold one whole number per robot",
    ),
    "plans past the targets": (
        lambda m: {"swarm.driver.strategy._planned": m["swarm.driver.strategy._planned"] + 10**6},
        "_planned names a target that does not exist",
    ),
    "movers without targets": (
        lambda m: {"swarm.driver.target": np.full_like(m["swarm.driver.target"], -1)},
        "target disagrees with the robots' states",
    ),
    "targets filled by nobody": (
        lambda m: {"swarm.filled": np.ones_like(m["swarm.filled"])},
        "filled marks a target that no settled robot rests on",
    ),
    "a fault log of words": (
        lambda m: {"swarm.faults.log": [dict.fromkeys(LOG_KEYS, "x")]},
        "log is not a list of fault entries",
    ),
    "a saved setting out of range": (  # was blamed on --failure-rate, with no file named
        lambda m: {"config.failure_rate": 2.0},
        "s.state: failure_rate must be a number from 0 up to",
    ),
    "a value named with its file": (
        lambda m: {"swarm.wander_rate": 7.0},
        "s.state: damaged state: swarm.wander_rate is 7.0",
    ),
    "a robot under way going nowhere": (  # the fuzz (seed 41): 4 overlaps within 8 steps
        lambda m: {"swarm.direction": np.where(m["swarm.ahead"] > 0, 0, m["swarm.direction"])},
        "direction is none for a robot with cells reserved ahead",
    ),
    "a robot at rest between cells": (
        lambda m: {"swarm.offset": np.where(m["swarm.ahead"] == 0, 0.5, m["swarm.offset"])},
        "offset or speed puts a robot with no cell reserved on its way",
    ),
    "robots lost that are there": (
        lambda m: {"swarm.faults.lost_at": np.zeros_like(m["swarm.faults.lost_at"])},
        "lost_at disagrees with which robots are lost",
    ),
}


@pytest.mark.parametrize("name", sorted(CRAFTED))
def test_a_crafted_value_out_of_range_is_refused_before_the_first_step(tmp_path, name):
    """Issue 29, case 12: a state whose values were out of range, with a checksum made to
    match, crashed at the first step or reported "formed ... 136 overlaps" and "formed in
    10^100 steps" (exit 0). Every value is now checked against the rest on load."""
    path, _ = saved_state(tmp_path)
    _, members = state_members(path)
    change, message = CRAFTED[name]
    path.write_bytes(changed_state(path, change(members)))
    with pytest.raises(InputError, match=re.escape(message)):
        resume(path)


def test_a_state_member_that_unpacks_past_its_run_is_refused_before_it_is_unpacked(
    tmp_path, monkeypatch
):
    """Issue 29, case 10: a 2.9 MB state with a member that unpacked to 3 GB took 3 GB and 9 s
    before it was refused, though a state's sizes are promised to be checked before anything is
    decompressed. The sizes its arrays declare are now held against what a run of the world
    its manifest describes can keep, before any array is read."""
    import numpy.lib.format as npy

    path, _ = saved_state(tmp_path)
    manifest, members = state_members(path)
    cells = int(np.prod(manifest["values"]["swarm.world.size"]))
    members["swarm.driver.planner.rows"] = np.zeros((20_000, cells))  # zeros pack to nothing
    path.write_bytes(state_bytes(manifest, members))
    assert path.stat().st_size < 1_000_000
    read = []

    def reading(*args, **kwargs):
        read.append(args[0].name)
        return real(*args, **kwargs)

    real = npy.read_array
    monkeypatch.setattr(npy, "read_array", reading)
    with pytest.raises(InputError, match=r"s\.state: state file too large for its run \("):
        load_state(path)
    assert read == ["manifest.npy"]  # and no array


@pytest.mark.parametrize(
    "version, message",
    [('"3"', "its format version is not a number"), ("99", "format version 99; this")],
)
def test_a_state_of_another_version_says_which(tmp_path, version, message):
    """Issue 29, case 13: a version of '3' read "format version '3'; this reads version 3"."""
    path, _ = saved_state(tmp_path)
    rewritten(path, lambda text: re.sub(r'"version": \d+', f'"version": {version}', text))
    with pytest.raises(InputError, match=re.escape(message)):
        load_state(path)

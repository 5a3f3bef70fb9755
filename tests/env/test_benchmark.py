"""The benchmark: a task's episodes are decided by (task, seed), scoring gives the same bytes
for the same seeds, every baseline runs through the environment, and the leaderboard in docs/
is the one its results make."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from swarmshape.cli import main
from swarmshape.env.benchmark import (
    TASKS,
    Context,
    Random,
    Scripted,
    Task,
    evaluate,
    leaderboard,
    local_programs,
    policy,
    tasks,
    to_json,
    to_markdown,
)
from swarmshape.env.benchmark.score import environment
from swarmshape.env.benchmark.suite import table
from swarmshape.errors import InputError

DOCS = Path(__file__).resolve().parents[2] / "docs"
SMALL = Task("small-star", "star.png", 40, 300, (0, 1))
NOISY = Task("small-noisy", "star.png", 40, 300, (0,), distance_noise=0.1, msg_loss=0.1)


def test_the_same_seeds_give_the_same_bytes_and_other_seeds_other_ones():
    one = evaluate(Random(), [SMALL, NOISY], seeds=[3])
    two = evaluate(Random(), [SMALL, NOISY], seeds=[3])
    other = evaluate(Random(), [SMALL, NOISY], seeds=[4])
    assert to_json(one) == to_json(two) and to_markdown(one) == to_markdown(two)
    assert to_json(one) != to_json(other)


def test_the_leaderboards_episodes_are_reproduced_byte_for_byte():
    """The committed results name every episode; rerun two of them here."""
    for name in ("random", "learned"):
        saved = json.loads((DOCS / "benchmark" / f"{name}.json").read_text())
        again = evaluate(policy(name), tasks("star-100"), seeds=[0])
        first = saved["tasks"]["star-100"]["episodes"][0]
        assert json.dumps(again["tasks"]["star-100"]["episodes"][0]) == json.dumps(first)


def test_what_a_policy_broadcasts_changes_what_robots_hear_never_where_they_go():
    class Talking(Random):
        message_size = 3

        def __call__(self, obs):
            moves = super().__call__(obs)
            return np.column_stack([moves, np.zeros((len(obs), 3), dtype=np.int64)])

    quiet, talking = evaluate(Random(), [SMALL], [5]), evaluate(Talking(), [SMALL], [5])
    for key in ("coverage", "steps_run", "claims_refused", "makespan_lower_bound"):
        assert (
            quiet["tasks"][SMALL.name]["episodes"][0][key]
            == (talking["tasks"][SMALL.name]["episodes"][0][key])
        )
    assert talking["tasks"][SMALL.name]["messages"] == 40 * 300


def test_figures_are_read_from_the_swarm():
    class Still:
        name = "still"

        def __call__(self, obs):
            return np.zeros(len(obs), dtype=np.int64)

    results = evaluate(Still(), [SMALL], [0])["tasks"][SMALL.name]
    assert results["coverage"] == 0.0 and results["success_rate"] == 0.0
    assert results["steps_to_form"] is None and results["steps"] == SMALL.steps
    assert results["claims_refused"] == 0
    assert results["episodes"][0]["steps_run"] == SMALL.steps


@pytest.mark.parametrize("program", local_programs())
def test_every_local_program_runs_as_a_policy_through_the_environment(program):
    short = Task("short", "letter-s.png", 30, 25, (0,))
    results = evaluate(Scripted(program), [short])["tasks"]["short"]
    assert results["messages"] == 30 * 25


def test_a_scripted_program_forms_a_shape_through_the_environment():
    results = evaluate(Scripted("local-swap"), [SMALL], [0])["tasks"][SMALL.name]
    assert results["success_rate"] == 1.0 and results["makespan_ratio"] >= 1.0


def test_a_policy_is_named_or_loaded_from_a_file(tmp_path):
    assert isinstance(policy("random"), Random) and isinstance(policy("local-swap"), Scripted)
    code = tmp_path / "mine.py"
    code.write_text("import numpy as np\nclass Still:\n    def __call__(self, obs):\n"
                    "        return np.zeros(len(obs), dtype=np.int64)\n")  # fmt: skip
    assert policy(f"{code}:Still").name == "Still"
    with pytest.raises(InputError, match="unknown policy"):
        policy("nothing")
    with pytest.raises(InputError, match="has no Other"):
        policy(f"{code}:Other")


def test_wrong_actions_are_one_clear_error():
    with pytest.raises(InputError, match="policy wrong: actions must be integers of shape"):
        evaluate(Wrong(), [SMALL], [0])


class Wrong:
    name = "wrong"

    def __call__(self, obs):
        return np.zeros(3)


def test_the_command_prints_a_row_and_writes_its_files(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["benchmark", "random", "--tasks", "star-100", "--seeds", "0-1",
                 "--json", str(out)]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert "| random | " in printed and "| star-100 | 100 | 2 |" in printed
    saved = json.loads(out.read_text())
    assert saved["tasks"]["star-100"]["seeds"] == [0, 1]
    assert main(["benchmark", "random", "--tasks", "star-100", "--json", str(out)]) == 2
    assert "add --force" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["nothing"], "unknown policy 'nothing'"),
        (["random", "--tasks", "star-1"], "unknown task 'star-1'"),
        (["random", "--seeds", "2-1"], "low-high ascending"),
        (["random", "--seeds", "a"], "expected seeds like"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    try:
        code = main(["benchmark", *argv])
    except SystemExit as exit:  # argparse's own errors
        code = exit.code
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_without_a_policy_the_command_lists_the_tasks(capsys):
    assert main(["benchmark"]) == 0
    assert capsys.readouterr().out == table()


def test_docs_show_the_suite_and_the_leaderboard_its_results_make():
    page = (DOCS / "benchmark.md").read_text()
    assert table() in page
    rows = [json.loads((DOCS / "benchmark" / f"{name}.json").read_text())
            for name in ("random", *local_programs(), "learned")]  # fmt: skip
    assert leaderboard(rows) in page
    assert leaderboard(rows) in (DOCS.parent / "README.md").read_text()
    for row in rows:
        assert list(row["tasks"]) == list(TASKS)


def test_context_gives_each_episode_its_own_generator():
    env = environment(Random(), SMALL)
    made = [
        Context(SMALL, seed, 40, env.layout, env.blueprint).rng().random() for seed in (1, 1, 2)
    ]
    assert made[0] == made[1] != made[2]

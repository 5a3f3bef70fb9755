"""The figure scripts run. No other test runs them, and one broke unnoticed (`scripts/faults.py`
after `scripts/bench.py`'s `world_of` lost its robot count) until its figure was wanted."""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

import numpy as np
from PIL import Image

from swarmshape.core.local import QUIET
from swarmshape.core.shape import Shape
from tests.conftest import python, script

ROOT = Path(__file__).resolve().parent.parent


def test_the_fault_figures_run_on_a_small_disc(tmp_path):
    out = tmp_path / "faults.json"
    done = run_script("faults.py", "--strategies", "optimal", "--cells", "40", "--no-pictures",
                      "--out", str(out))  # fmt: skip
    assert done.returncode == 0, done.stderr
    figures = json.loads(out.read_text())
    healed, short = figures["optimal"]["with spares"], figures["optimal"]["no spares"]
    assert healed["random"]["final_coverage"] == 1.0 and healed["random"]["overlaps"] == 0
    assert figures["on_loss"] == "keep" and short["random"]["final_scale"] == 1.0
    assert short["random"]["cells_left_open"] == short["random"]["robots_removed"]


def test_the_heal_table_runs_and_re_forms_smaller_when_asked(tmp_path):
    """Its default output was None (it crashed at the end of an hour's runs), and it ignored
    `--on-loss`, so under the default keep a loss with no spares was 'healed' at once."""
    out = tmp_path / "heal.json"
    command = ["--heal", "--strategies", "optimal", "--shapes", "square.png", "--random", "0"]
    command += ["--seeds", "2", "--jobs", "1", "--on-loss", "rescale", "--out", str(out)]
    done = run_script("faults.py", *command)
    assert done.returncode == 0, done.stderr
    runs = json.loads(out.read_text())
    assert len(runs) == 2 and all(run["healed"] for run in runs)
    assert all(run["scale"] < 1 and run["heal_steps"] > 0 for run in runs)


STILL = """
import numpy as np
from swarmshape import Program


class Still(Program):
    name = "still"
    description = "knows where it is, and never moves"

    def act(self, sense, memory, rng):
        return np.zeros(len(sense), dtype=np.int64), np.zeros((len(sense), 0), dtype=np.int64)

    def estimate(self, memory):
        return np.ones(len(memory), dtype=bool), np.zeros((len(memory), 2), dtype=np.int64)
"""


def test_where_the_steps_go_counts_a_robot_that_never_moves_as_standing_every_step(tmp_path):
    """16 robots on a 4 by 4 square, none finished, stand until the run comes to rest."""
    program = tmp_path / "still.py"
    program.write_text(STILL)
    done = run_script("where_steps_go.py", "shapes/square.png", "--cells", "4", "--seeds", "1",
                      "--strategy", f"{program}:Still")  # fmt: skip
    assert done.returncode == 0, done.stderr
    counts = dict(re.findall(r"^(\w[\w ]*?) +([\d,]+) +[\d.]+%", done.stdout, re.MULTILINE))
    standing = f"{16 * QUIET:,}"
    assert counts == {"without bearings": "0", "under way": "0", "starting off": "0",
                      "standing": standing}  # fmt: skip
    central = run_script("where_steps_go.py", "shapes/square.png", "--strategy", "optimal")
    assert central.returncode == 2 and central.stderr.count("\n") == 1, central.stderr


def run_script(name: str, *args: str) -> subprocess.CompletedProcess:
    """``python scripts/NAME ARGS`` from the repository's root, headless."""
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    return python(f"scripts/{name}", *args, cwd=ROOT, env=env, timeout=300)


def pictures_script(*args: str) -> str:
    done = run_script("make_docs_pictures.py", *args)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_every_picture_in_docs_has_a_maker_that_the_readme_names():
    made = set(pictures_script("--list").split())
    readme = (ROOT / "README.md").read_text()
    shown = set(re.findall(r"\(docs/([\w.-]+\.(?:png|gif))\)", readme))
    kept = {path.name for pattern in ("*.png", "*.gif") for path in (ROOT / "docs").glob(pattern)}
    assert shown and shown <= made and kept <= made, (shown - made, kept - made)
    assert "scripts/make_docs_pictures.py" in readme


def test_the_window_pictures_are_made_anew(tmp_path):
    pictures_script("editor.png", "star-concurrent.png", "--out", str(tmp_path))
    for name in ("editor.png", "star-concurrent.png"):
        with Image.open(tmp_path / name) as image:
            assert image.size == (1280, 800)
            assert len(image.convert("RGB").getcolors(1 << 16)) > 10, "a drawn window"


def test_the_sprite_loop_beside_the_benchmark_moves_robots_a_cell_a_step_and_never_onto_one(
    tmp_path,
):
    """`bench.py`'s side-by-side row times it: it must do what it says. One robot goes along x
    and then y to its goal, another waits behind one standing on the next cell for good."""
    scenario = tmp_path / "scenario.npz"
    start = np.array([[0, 0], [0, 4], [1, 4]])
    goal = np.array([[3, 2], [3, 4], [1, 4]])
    np.savez(scenario, size=np.array([5, 5]), start=start, goal=goal)
    loops = script("reference_loops")
    assert loops.sprites(scenario, 2)[1].tolist() == [[2, 0], [0, 4], [1, 4]]
    assert loops.sprites(scenario, 10)[1].tolist() == [[3, 2], [0, 4], [1, 4]]


def test_the_benchmarks_tables_are_the_ones_its_results_make():
    for name in ("leaderboard.py", "generalisation.py"):
        done = run_script(name, "--check")
        assert done.returncode == 0, done.stdout + done.stderr


def test_the_comparison_table_is_made_from_a_sweeps_rows():
    done = run_script("compare.py", "sweeps/local-vs-optimal.csv")
    assert done.returncode == 0, done.stderr
    rows = {tuple(line.split(" | ")[:3]): line for line in done.stdout.splitlines()}
    small = rows["| letter-s.png", "98", "`optimal`"].split(" | ")
    assert small[3:6] == ["3/3", "51 (50 to 85)", "1.5 (1.5 to 2.6)"]
    assert rows["| letter-s.png", "1,018", "`local-swap`"].split(" | ")[6:8] == [
        "1.54 (1.44 to 1.57)",
        "1.00",
    ]


def test_the_fuzz_of_programs_reports_a_case_that_does_not_form_and_fails():
    """Case 5 of the fuzz (a stall of 19 % of the robots at step 55) stands short of its shape
    at 200 steps: one line names the case and says why, and the exit status is 1."""
    command = ["mean-shift", "--first", "5", "--cases", "1", "--max-steps", "200"]
    done = run_script("fuzz_programs.py", *command)
    assert done.returncode == 1, done.stderr
    (line, summary) = done.stdout.splitlines()
    assert line.startswith("case 5 (84 cells, 88 robots, noise 0, faults [FaultEvent(step=55")
    assert re.search(r": not formed after 200 steps \(coverage \d+%\)$", line), line
    assert summary == "mean-shift: 1 cases, 1 with a problem"


def test_the_fuzz_of_a_program_that_grows_from_the_seeds_draws_only_what_it_can_form():
    """Drawn whole, case 3's shape has cells that no swarm growing from the seeds reaches, so
    `self-assembly` stood short on it (and on nearly every case) whatever it did."""
    rng = np.random.default_rng(3)  # case 3's first draws, as the script makes them
    height, width = rng.integers(3, 13, size=2)
    grid = rng.random((height, width)) < rng.uniform(0.4, 0.95)
    grid[rng.integers(height), rng.integers(width)] = True
    whole, solid = Shape(grid).count, Shape(grid).solid().count
    assert solid < whole
    command = ["self-assembly", "--first", "3", "--cases", "1", "--max-steps", "1"]
    done = run_script("fuzz_programs.py", *command)
    assert done.stdout.startswith(f"case 3 ({solid} cells, "), done.stdout + done.stderr

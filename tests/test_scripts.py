"""The figure scripts run. No other test runs them, and one broke unnoticed (`scripts/faults.py`
after `scripts/bench.py`'s `world_of` lost its robot count) until its figure was wanted."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_fault_figures_run_on_a_small_disc(tmp_path):
    out = tmp_path / "faults.json"
    command = [sys.executable, "scripts/faults.py", "--strategies", "optimal", "--cells", "40"]
    command += ["--no-pictures", "--out", str(out)]
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    subprocess.run(command, cwd=ROOT, env=env, check=True, capture_output=True, timeout=300)
    healed = json.loads(out.read_text())["optimal"]["with spares"]
    assert healed["random"]["final_coverage"] == 1.0 and healed["random"]["overlaps"] == 0

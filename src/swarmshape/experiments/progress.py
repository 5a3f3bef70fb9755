"""A one-line progress bar on stderr, for headless runs and sweeps; silent when stderr is not
a terminal (pipes, logs, CI), so output files and captured text stay clean."""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from swarmshape.core.swarm import Swarm

WIDTH = 30
PAUSE = 0.25
"""Seconds between redraws: often enough to watch, rarely enough to cost nothing."""


class ProgressBar:
    def __init__(self) -> None:
        self.live = sys.stderr.isatty()
        self._drawn = 0.0

    def show(self, fraction: float, text: str, *, now: bool = False) -> None:
        """Redraw with `fraction` (0..1) done and `text` after the bar."""
        moment = time.monotonic()
        if not self.live or (moment - self._drawn < PAUSE and not now):
            return
        self._drawn = moment
        bar = "#" * int(WIDTH * min(max(fraction, 0.0), 1.0))
        sys.stderr.write(f"\r[{bar:<{WIDTH}}] {text}")
        sys.stderr.flush()

    def done(self) -> None:
        if self.live:
            sys.stderr.write("\n")


class RunProgress:
    """A run's coverage as a progress bar: an observer for `swarmshape.runs.Runner`."""

    def __init__(self) -> None:
        self.bar = ProgressBar()

    def capture(self, swarm: Swarm) -> None:
        coverage = swarm.filled.mean()
        self.bar.show(coverage, f"coverage {100 * coverage:5.1f}%  step {swarm.step_count}")

    def close(self, swarm: Swarm) -> None:
        self.bar.done()

"""Signs of life on stderr, for headless runs and sweeps: a one-line bar on a terminal, and off
a terminal (pipes, logs, CI) a plain line every `QUIET_LINES` seconds, so that a long run is
never silent and a short one prints nothing extra."""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING

from swarmshape.runs import Observer

if TYPE_CHECKING:
    from swarmshape.core.swarm import Swarm

WIDTH = 30
PAUSE = 0.25
"""Seconds between redraws of the bar: often enough to watch, rarely enough to cost nothing."""
QUIET_LINES = 10.0
"""Seconds between progress lines when stderr is not a terminal."""


class ProgressBar:
    def __init__(self) -> None:
        self.live = sys.stderr.isatty()
        self._shown = time.monotonic()
        self._drawn = False

    def show(self, fraction: float, text: str, *, now: bool = False) -> None:
        """Show `fraction` (0..1) done and `text`: redraw the bar, or off a terminal write a
        line if it has been a while."""
        moment = time.monotonic()
        wait = PAUSE if self.live else QUIET_LINES
        if moment - self._shown < wait and not (now and self.live):
            return
        self._shown = moment
        if self.live:
            bar = "#" * int(WIDTH * min(max(fraction, 0.0), 1.0))
            sys.stderr.write(f"\r[{bar:<{WIDTH}}] {text}")
            self._drawn = True
        else:
            sys.stderr.write(f"swarmshape: {text}\n")
        sys.stderr.flush()

    def done(self) -> None:
        if self._drawn:
            sys.stderr.write("\n")
            self._drawn = False


class RunProgress(Observer):
    """A run's coverage as progress: an observer for `swarmshape.runs.Runner`."""

    def __init__(self) -> None:
        self.bar = ProgressBar()

    def capture(self, swarm: Swarm) -> None:
        coverage = swarm.filled.mean()
        self.bar.show(coverage, f"step {swarm.step_count}, coverage {100 * coverage:5.1f}%")

    def close(self, swarm: Swarm) -> None:
        self.bar.done()

    def discard(self) -> None:
        self.bar.done()

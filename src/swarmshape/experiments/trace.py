"""Per-step traces: one CSV row every few steps, with the same figures as the metrics file.

Rows go to a temporary file beside the target as the run goes; it takes the target's name
when the run ends and is removed if the run is abandoned, so no half-written trace is left.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

from swarmshape.core.metrics import coverage, entering, iou, uniformity
from swarmshape.core.states import MOVING, SETTLED, STALLED, WAITING, WANDERING
from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.io.files import StreamedFile
from swarmshape.runs import Observer

COUNTS = {"moving": MOVING, "settled": SETTLED, "waiting": WAITING, "wandering": WANDERING}


def trace_row(swarm: Swarm) -> dict[str, Any]:
    """The run's figures now: totals, then the same per group (``NAME.figure``)."""
    row: dict[str, Any] = {
        "step": swarm.step_count,
        "coverage": coverage(swarm),
        "entering": entering(swarm),
        "uniformity": uniformity(swarm),
        "iou": iou(swarm),
        **{name: int((swarm.state == state).sum()) for name, state in COUNTS.items()},
        "messages": swarm.driver.messages_sent,
        "overlaps": int(swarm.overlap_total),
        "stalled": int((swarm.state == STALLED).sum()),
        "lost": swarm.faults.lost,
    }
    for g, placed in enumerate(swarm.world.groups):
        mine = swarm.group == g
        row[f"{placed.name}.coverage"] = coverage(swarm, g)
        row[f"{placed.name}.entering"] = entering(swarm, g)
        row[f"{placed.name}.uniformity"] = uniformity(swarm, g)
        row[f"{placed.name}.iou"] = iou(swarm, g)
        for name, state in COUNTS.items():
            row[f"{placed.name}.{name}"] = int((mine & (swarm.state == state)).sum())
        row[f"{placed.name}.overlaps"] = int(swarm.overlaps[g])
    return row


class Trace(Observer):
    """Writes `trace_row` every `every` steps, and always for the last step."""

    def __init__(self, path: Path, every: int = 1) -> None:
        if every < 1:
            raise InputError(f"--trace-every must be at least 1, got {every}")
        self.every = every
        self._file = StreamedFile(path)
        self._writer: csv.DictWriter | None = None
        self._last = -1

    def capture(self, swarm: Swarm, *, force: bool = False) -> None:
        if swarm.step_count == self._last or (swarm.step_count % self.every and not force):
            return
        row = trace_row(swarm)
        try:
            if self._writer is None:
                self._writer = csv.DictWriter(self._file.handle, fieldnames=list(row))
                self._writer.writeheader()
            self._writer.writerow(row)
        except OSError as error:
            raise self._file.failed(error) from None
        self._last = swarm.step_count

    def close(self, swarm: Swarm) -> None:
        """Write the final row and give the file its name."""
        self.capture(swarm, force=True)
        self._file.commit()

    def discard(self) -> None:
        """Remove the rows written so far (an existing file keeps its old content)."""
        self._file.discard()

"""Every robot's position per step, for analysis elsewhere: ``--positions FILE``.

A ``.npz`` file holds arrays ``step (k,)``, ``position (k, robots, 2)`` (square centres in
cells, float32), ``state (k, robots)`` and ``group (robots,)``; a ``.csv`` file has one row per
robot per kept step: ``step,robot,group,x,y,state``. The CSV is written as the run goes; the
arrays are kept in memory, and a run long enough to pass `MAX_VALUES` keeps every other step
(the ``step`` array says which).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.io.files import StreamedFile, atomic_write
from swarmshape.runs import Observer

SUFFIXES = (".npz", ".csv")
MAX_VALUES = 200_000_000
"""Positions kept in memory for an .npz (about 1.6 GB with states); beyond, the stride doubles."""


class Positions(Observer):
    """Writes the robots' positions every `every` steps, and at the last step."""

    def __init__(self, path: Path, every: int = 1) -> None:
        if every < 1:
            raise InputError(f"--positions-every must be at least 1, got {every}")
        if path.suffix.lower() not in SUFFIXES:
            raise InputError(f"{path}: --positions writes .npz or .csv files; pick one of those")
        self.path, self.every = path, every
        self._csv = StreamedFile(path) if path.suffix.lower() == ".csv" else None
        self._steps: list[int] = []
        self._positions: list[np.ndarray] = []
        self._states: list[np.ndarray] = []
        self._group: np.ndarray | None = None

    def capture(self, swarm: Swarm, *, force: bool = False) -> None:
        step = swarm.step_count
        if (self._steps and self._steps[-1] == step) or (step % self.every and not force):
            return
        position = swarm.positions().astype(np.float32)
        self._steps.append(step)
        self._group = swarm.group
        if self._csv is not None:
            self._write_rows(step, position, swarm)
            return
        self._positions.append(position)
        self._states.append(swarm.state.copy())
        if len(self._positions) * position.size > MAX_VALUES:
            last = self._steps[-1]
            keep = [i for i, s in enumerate(self._steps) if s % (2 * self.every) == 0 or s == last]
            self._steps = [self._steps[i] for i in keep]
            self._positions = [self._positions[i] for i in keep]
            self._states = [self._states[i] for i in keep]
            self.every *= 2

    def _write_rows(self, step: int, position: np.ndarray, swarm: Swarm) -> None:
        robots = np.arange(len(position))
        rows = np.column_stack([np.full(len(position), step), robots, swarm.group])
        lines = [
            f"{s},{r},{g},{x:.6g},{y:.6g},{state}\n"
            for (s, r, g), (x, y), state in zip(
                rows.tolist(), position.tolist(), swarm.state.tolist(), strict=True
            )
        ]
        try:
            if len(self._steps) == 1:
                self._csv.handle.write("step,robot,group,x,y,state\n")
            self._csv.handle.writelines(lines)
        except OSError as error:
            raise self._csv.failed(error) from None

    def close(self, swarm: Swarm) -> None:
        self.capture(swarm, force=True)
        if self._csv is not None:
            self._csv.commit()
            return
        arrays = {
            "step": np.array(self._steps, dtype=np.int64),
            "position": np.stack(self._positions),
            "state": np.stack(self._states),
            "group": self._group,
        }

        def write(tmp: str) -> None:
            with open(tmp, "wb") as handle:
                np.savez_compressed(handle, **arrays)

        atomic_write(self.path, write)

    def discard(self) -> None:
        if self._csv is not None:
            self._csv.discard()

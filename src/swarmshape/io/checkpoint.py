"""Saving and loading a whole run, to resume it exactly: every array, the strategy, the
message queue, the path fields and the random generator's state go into one file.

The format is Python's pickle behind a swarmshape header, so load only state files you trust.
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmshape.core.swarm import Swarm
from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write

HEADER = b"swarmshape state 1\n"


@dataclass(frozen=True)
class Saved:
    """A run as saved: the swarm, and the description it was built from."""

    swarm: Swarm
    config: dict[str, Any]


def save_state(swarm: Swarm, path: Path, config: dict[str, Any]) -> None:
    """Write the run to `path` atomically."""
    saved = Saved(swarm, config)
    payload = HEADER + pickle.dumps(saved, protocol=pickle.HIGHEST_PROTOCOL)
    atomic_write(path, lambda tmp: Path(tmp).write_bytes(payload))


def load_state(path: Path) -> Saved:
    """Read a run saved by `save_state`; anything else is refused with a clear message."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{path}: no such state file") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read state ({error.strerror})") from None
    if not data.startswith(HEADER):
        raise InputError(f"{path}: not a swarmshape state file (write one with --save-state)")
    try:
        saved = pickle.loads(data[len(HEADER) :])
    except Exception as error:  # a truncated or damaged file can fail in many ways
        raise InputError(f"{path}: damaged state file ({type(error).__name__})") from None
    if not isinstance(saved, Saved):
        raise InputError(f"{path}: not a swarmshape state file")
    return saved

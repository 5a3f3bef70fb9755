"""Faults: robots that fail during a run, and the record of how the shape healed.

Three kinds of fault, each drawn from the run's one random generator so a run repeats per seed:

- ``remove``: robots vanish (a fraction or a number of them, at a step, at random or inside a
  rectangle or disc of cells). They leave the lattice and take the state `LOST`.
- ``stall``: robots stop for good where they are (a failed motor). They take the state
  `STALLED`, finish the run of cells they had already reserved, and hold their last cell as an
  obstacle the others route around. A stalled robot on a target cell is lost coverage: that
  target counts as unreachable (see `Swarm.dead`), never as filled.
- a failure rate: each robot still present fails (is removed) with probability ``p`` per step.

Removed robots keep their index and their arrays, marked `LOST`, rather than being compacted
away. Every per-robot array (the swarm's, the driver's, a strategy's own, the message queue's
recipients, the lattice's holders and leader links) stays valid as it is, a saved run keeps the
same array shapes from start to end, and "robots are conserved except those removed" is one
count: present + lost = agents. What a lost robot costs is a few bytes, and skipping it in the
audit, the drawing and the metrics.

The plain-value forms here (``"0.2@300"``, ``"X,Y,W,H@STEP"``, a scenario's ``[[faults]]``
tables) are parsed into `FaultEvent`; a bad one is one `InputError` line naming where it came
from. The swarm asks `Faults` what is due each step and applies it through `Swarm.fail`; `Faults`
holds the schedule, the rate and the log, and knows nothing of the swarm.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmshape.core.options import NUMBER, Spec
from swarmshape.core.snapshot import Snapshot
from swarmshape.core.states import LOST, STALLED
from swarmshape.errors import InputError

KINDS = ("remove", "stall")
"""Event kinds a schedule may hold (the log also says ``rate`` and ``window``)."""

MAX_EVENTS = 10_000
MAX_STEP = 10**12
LOG_KEYS = ("step", "kind", "robots", "coverage_before", "coverage_after", "recovered_at",
            "recovery_steps", "scale")  # fmt: skip
"""One fault's entry in the metrics: what happened, and when the shape was whole again."""


class FaultError(InputError):
    """A fault event or rate that cannot be used; the message says where and why."""


@dataclass(frozen=True)
class FaultEvent:
    """At `step` (after that many steps), `kind` strikes `amount` of the robots present.

    `amount` is a fraction in (0, 1] (a float) or a number of robots (an int); `region`, if
    given, limits the event to robots whose cell lies in a rectangle ``(x, y, w, h)`` or a disc
    ``(x, y, r)`` of cells (centre x, y), and `amount` then defaults to all of them.
    """

    step: int
    kind: str = "remove"
    amount: float | int = 1.0
    region: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        where = f"fault at step {self.step}"
        if type(self.step) is not int or not 0 <= self.step <= MAX_STEP:
            raise FaultError(
                f"a fault's step must be a whole number from 0 to {MAX_STEP:,}, got {self.step!r}"
            )
        if self.kind not in KINDS:
            raise FaultError(f"{where}: kind {self.kind!r} is not one of {', '.join(KINDS)}")
        amount = self.amount
        if isinstance(amount, bool) or not isinstance(amount, int | float):
            raise FaultError(f"{where}: amount must be a fraction or a number, got {amount!r}")
        if isinstance(amount, float) and not (math.isfinite(amount) and 0 < amount <= 1):
            raise FaultError(f"{where}: a fraction of robots must be above 0 and at most 1")
        if isinstance(amount, int) and amount < 1:
            raise FaultError(f"{where}: a number of robots must be at least 1, got {amount}")
        region = self.region
        if region is not None:
            if len(region) not in (3, 4) or not all(type(v) is int for v in region):
                raise FaultError(
                    f"{where}: a region is X,Y,W,H (a rectangle) or X,Y,R (a disc) in whole "
                    f"cells, got {region!r}"
                )
            if any(v < 0 for v in region) or any(v < 1 for v in region[2:]):
                raise FaultError(
                    f"{where}: a region needs x, y of 0 or more and sizes of 1 or more"
                )

    def values(self) -> dict[str, Any]:
        """This event as plain values (a scenario's table, a saved run's config)."""
        plain: dict[str, Any] = {"step": self.step, "kind": self.kind, "amount": self.amount}
        if self.region is not None:
            plain["region"] = list(self.region)
        return plain

    def robots(self, state: np.ndarray, cell: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The robots this event strikes now, given every robot's state and cell, drawn from
        the run's generator."""
        alive = state != LOST
        if self.kind == "stall":
            alive &= state != STALLED
        candidates = np.flatnonzero(alive)
        if self.region is not None:
            cells = cell[candidates]
            if len(self.region) == 4:
                x, y, w, h = self.region
                inside = (cells >= (x, y)).all(axis=1) & (cells < (x + w, y + h)).all(axis=1)
            else:
                x, y, r = self.region
                inside = ((cells + 0.5 - (x + 0.5, y + 0.5)) ** 2).sum(axis=1) <= r * r
            candidates = candidates[inside]
        if isinstance(self.amount, float):
            count = round(self.amount * len(candidates))
        else:
            count = min(self.amount, len(candidates))
        if count >= len(candidates):
            return candidates
        return np.sort(rng.choice(candidates, count, replace=False))


def parse_event(text: str, kind: str, option: str) -> FaultEvent:
    """``AMOUNT@STEP`` (a fraction like 0.2, or a number of robots like 50) as an event."""
    amount, step = _split(text, option, "FRACTION@STEP, e.g. 0.2@300")
    try:
        value: float | int = int(amount) if amount.strip().isdecimal() else float(amount)
    except ValueError:
        raise FaultError(f"{option} expects FRACTION@STEP, e.g. 0.2@300, got {text!r}") from None
    try:
        return FaultEvent(step, kind, value)
    except FaultError as error:
        raise FaultError(f"{option} {text}: {_reason(error)}") from None


def parse_region(text: str, option: str = "--fail-region") -> FaultEvent:
    """``X,Y,W,H@STEP`` (a rectangle of cells) or ``X,Y,R@STEP`` (a disc) as a removal."""
    region, step = _split(text, option, "X,Y,W,H@STEP, e.g. 10,5,8,6@300")
    try:
        numbers = tuple(int(part) for part in region.split(","))
    except ValueError:
        raise FaultError(
            f"{option} expects X,Y,W,H@STEP in whole cells, e.g. 10,5,8,6@300, got {text!r}"
        ) from None
    try:
        return FaultEvent(step, "remove", 1.0, numbers)
    except FaultError as error:
        raise FaultError(f"{option} {text}: {_reason(error)}") from None


FAILURE_RATE = Spec(
    "failure_rate",
    NUMBER,
    0.0,
    "each robot fails (is removed) with this probability per step",
    at_least=0.0,
    below=1.0,
)


def events_from_values(values: Any, where: str) -> tuple[FaultEvent, ...]:
    """Events from plain values: a list of tables with ``step``, ``kind``, ``amount`` and
    ``region`` (a scenario's ``[[faults]]``, a saved run's config), or of ``AMOUNT@STEP`` text."""
    if not isinstance(values, list | tuple):
        raise FaultError(f"{where} must be a list of fault events, got {values!r}")
    if len(values) > MAX_EVENTS:
        raise FaultError(f"{where} holds {len(values):,} events, more than {MAX_EVENTS:,}")
    events = []
    for index, value in enumerate(values):
        here = f"{where}[{index}]"
        if isinstance(value, FaultEvent):
            events.append(value)
            continue
        if isinstance(value, str):
            events.append(parse_event(value, "remove", here))
            continue
        if not isinstance(value, Mapping):
            raise FaultError(f"{here} must be a table with step, kind, amount, region")
        unknown = sorted(set(value) - {"step", "kind", "amount", "region"})
        if unknown:
            raise FaultError(f"{here}: unknown key {unknown[0]!r} (step, kind, amount, region)")
        if "step" not in value:
            raise FaultError(f"{here} needs a step")
        region = value.get("region")
        if region is not None and not isinstance(region, list | tuple):
            raise FaultError(f"{here}: region must be [x, y, w, h] or [x, y, r], got {region!r}")
        try:
            events.append(
                FaultEvent(
                    value["step"],
                    value.get("kind", "remove"),
                    value.get("amount", 1.0),
                    None if region is None else tuple(region),
                )
            )
        except FaultError as error:
            raise FaultError(f"{here}: {_reason(error)}") from None
    return tuple(events)


def _split(text: str, option: str, form: str) -> tuple[str, int]:
    """`text`'s part before its last @, and the step after it. A step is decimal digits, the
    ones int() reads (str.isdigit also takes superscripts and circled digits, which it does
    not), and no more of them than int() reads (4,300)."""
    head, at, step = text.rpartition("@")
    if not at or not step.strip().isdecimal() or not head:
        raise FaultError(f"{option} expects {form}, got {text!r}")
    try:
        return head, int(step)
    except ValueError:
        raise FaultError(f"{option} expects {form}, got a step {len(step):,} digits long") from None


def _reason(error: Exception) -> str:
    """An event's own complaint without its "fault at step N: " lead."""
    return str(error).split(": ", 1)[-1]


class Faults:
    """A swarm's faults: the schedule it was given, the failure rate, the log of what struck,
    and per robot the step it was lost (-1: present)."""

    def __init__(self, events: tuple[FaultEvent, ...] = (), rate: float = 0.0, robots: int = 0):
        self.events = tuple(sorted(events, key=lambda e: e.step))
        self.rate = FAILURE_RATE.check(rate)
        self.log: list[dict[str, Any]] = []
        self.lost_at = np.full(robots, -1, dtype=np.int64)

    @property
    def scheduled(self) -> bool:
        return bool(self.events) or self.rate > 0

    def ahead(self, step: int) -> bool:
        """Events remain at or after `step` (a run that formed is not over yet)."""
        return bool(self.events) and self.events[-1].step >= step

    def due(self, step: int) -> list[FaultEvent]:
        """The events that strike before step `step` + 1 (the swarm applies them in order)."""
        return [event for event in self.events if event.step == step]

    def rate_hits(self, state: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """The robots the failure rate removes this step (drawn for every robot, present or not,
        so the draws do not depend on who is left)."""
        if self.rate <= 0:
            return np.zeros(0, dtype=np.int64)
        return np.flatnonzero((rng.random(len(state)) < self.rate) & (state != LOST))

    def note(self, step: int, whole: bool) -> None:
        """After a step: faults whose shape is `whole` again (every target that the survivors
        can reach is filled) record when."""
        if not self.log or self.log[-1]["recovered_at"] is not None or not whole:
            return
        for entry in self.log:
            if entry["recovered_at"] is None:
                entry["recovered_at"] = step
                entry["recovery_steps"] = step - entry["step"]

    @property
    def lost(self) -> int:
        return int((self.lost_at >= 0).sum())

    def snapshot(self) -> dict[str, Any]:
        return {
            "events": [event.values() for event in self.events],
            "rate": self.rate,
            "log": [dict(entry) for entry in self.log],
            "lost_at": self.lost_at,
        }

    @classmethod
    def restored(cls, saved: Snapshot, robots: int, step: int) -> Faults:
        """The faults `snapshot` saved, of a run at `step`: every value in range."""
        try:
            events = events_from_values(saved.value("events"), "faults.events")
            faults = cls(events, saved.number("rate", 0, 1), robots)
        except FaultError as error:
            raise saved.error("events", f"are not fault events ({error})") from None
        faults.lost_at = saved.array("lost_at", np.int64, (robots,), -1, step)
        log = saved.value("log")
        if not isinstance(log, list) or not all(_logged(entry, robots, step) for entry in log):
            raise saved.error("log", "is not a list of fault entries")
        faults.log = [dict(entry) for entry in log]
        return faults


def _logged(entry: Any, robots: int, step: int) -> bool:
    """Whether `entry` is a fault's log entry (see `Swarm.fail`) of a run of `robots` at
    `step`: each value of its kind and in range, and its recovery after its fault."""
    if not isinstance(entry, dict) or set(entry) != set(LOG_KEYS):
        return False
    struck, recovered = entry["step"], entry["recovered_at"]
    shares = ("coverage_before", "coverage_after", "scale")
    if not (
        _whole(struck, 0, step)
        and isinstance(entry["kind"], str)
        and _whole(entry["robots"], 0, robots)
        and all(type(entry[key]) in (int, float) and 0 <= entry[key] <= 1 for key in shares)
    ):
        return False
    if recovered is None:
        return entry["recovery_steps"] is None
    return _whole(recovered, struck, step) and entry["recovery_steps"] == recovered - struck


def _whole(value: Any, low: int, high: int) -> bool:
    return type(value) is int and low <= value <= high

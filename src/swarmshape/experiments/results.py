"""A sweep's results CSV: a header, then one row per finished run, each added as its run ends
so that a killed sweep resumes where it stopped.

Many runs' worth of work sits in one file, so it is guarded: one sweep at a time writes it (a
lock beside it); a row cut short by kill -9 or a full disk is dropped when the sweep resumes
(and a row that fails to write is taken back at once); rows are added only under the header
of a swarmshape results file with the same settings, and any other file is replaced only with
`force`. At the end the rows are sorted by their runs' settings, numbers as numbers.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
from collections.abc import Collection, Iterable, Iterator, Mapping
from dataclasses import dataclass
from io import StringIO
from pathlib import Path
from typing import Any, BinaryIO

from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write, check_output, readable_file

START = b"run,"
MARKS = {"run", "curve_every", "coverage_curve", "wall_time"}
"""How a results file starts, and columns it always has: how one is told from other CSVs."""
FIRST = {"shape": 0, "strategy": 1, "agents": 2}
"""The settings rows are sorted by first, in this order; then the others by name, seed last."""

# csv's default limit, 131,072 characters a field, is less than a long run's coverage curve
csv.field_size_limit(2**31 - 1)


@contextlib.contextmanager
def open_results(
    path: Path,
    settings: list[str],
    *,
    runs: Collection[str] | None = None,
    force: bool = False,
    inputs: Mapping[Path, str] | None = None,
) -> Iterator[Results]:
    """`path` held for one sweep whose rows have the `settings` columns (``config.NAME``), and,
    if given, the `runs` keys (``run``).

    Checked before any run: the folder can be written, no other sweep holds the file, and the
    file is new, empty or a results file of the same settings whose rows are all whole and
    among `runs`; with `force` any other file is started over (the first row replaces it),
    but never one of the sweep's `inputs` (path: what it is to the sweep)."""
    path = Path(path)
    check_output(path, "--out", may_replace=True, inputs=inputs)
    with _lock(path):
        results = Results(path)
        try:
            results.take_over(settings, runs)
        except InputError:
            if not force:
                raise
        try:
            yield results
        finally:
            results.close()


class Results:
    """The rows a sweep adds to its file; made by `open_results`."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.header: list[str] | None = None
        """The file's columns; None until the first row when the file starts (over)."""
        self.done: set[str] = set()
        """The ``run`` keys already in the file."""
        self._fd: int | None = None
        self._size = 0

    def take_over(self, settings: list[str], runs: Collection[str] | None = None) -> None:
        """Read an existing file's runs, refusing one that is not a results file of these
        `settings` (and, if given, of these `runs`: rows of another sweep's would be merged
        with this one's without a word), and drop a last row cut short."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        runs = None if runs is None else set(runs)
        with _reading(self.path) as handle:
            scanned = _scan(handle, self.path)
            if scanned is None:
                raise InputError(
                    f"{self.path}: not a swarmshape sweep CSV; choose another --out, or add "
                    "--force to replace it"
                )
            header, records = scanned
            _same_settings(self.path, header.fields, settings)
            done, good = set(), header.end
            for record in records:
                if record.cut_short:
                    break  # its run is done again
                damage = _damage(header.fields, record)
                if damage:
                    raise InputError(
                        f"{self.path}: {damage}; remove that line, or add --force to start "
                        "the file over"
                    )
                if runs is not None and record.fields[0] not in runs:
                    raise InputError(
                        f"{self.path}: line {record.line} is a run this sweep does not have "
                        f"({_unlike(record.fields[0], runs)}); write to a new --out, or add "
                        "--force to start it over"
                    )
                done.add(record.fields[0])
                good = record.end
        if good < self.path.stat().st_size:
            os.truncate(self.path, good)
        self.header, self.done = header.fields, done
        self._open(good)

    def add(self, row: dict[str, Any]) -> None:
        """Add one finished run's row; it is on disk when this returns."""
        if self.header is None:
            self._start(row)
        elif list(row) != self.header:
            raise InputError(
                f"{self.path}: its columns are not the ones this version of swarmshape writes; "
                "write to a new --out"
            )
        else:
            self._write(_csv_text([list(row.values())]).encode())

    def finish(self) -> None:
        """Sort the rows by their runs' settings (numbers as numbers), keeping one row per run;
        a file already in order is left as it is."""
        if self.header is None:
            return
        with self.path.open("rb") as handle:
            header, records = _scan(handle, self.path)
            rows = [(_order(r.fields[0]), r.fields[0], r.start, r.end) for r in records]
        ordered = sorted(rows)
        kept = [row for i, row in enumerate(ordered) if i == 0 or row[1] != ordered[i - 1][1]]
        if kept == rows:
            return

        def write(tmp: str) -> None:
            with open(tmp, "wb") as out, self.path.open("rb") as source:
                out.write(source.read(header.end))
                for _, _, start, end in kept:
                    source.seek(start)
                    out.write(source.read(end - start))

        try:
            atomic_write(self.path, write)
        except OSError as error:
            raise _unwritable(self.path, error) from None

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def _start(self, row: dict[str, Any]) -> None:
        """The header and the first row, in one atomic write over whatever was there."""
        data = _csv_text([list(row), list(row.values())]).encode()
        try:
            atomic_write(self.path, lambda tmp: Path(tmp).write_bytes(data))
        except OSError as error:
            raise _unwritable(self.path, error) from None
        self.header = list(row)
        self._open(len(data))

    def _open(self, size: int) -> None:
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        self._size = size

    def _write(self, data: bytes) -> None:
        """Append `data` whole or not at all: when writing fails part way (a full disk, Ctrl+C)
        the part written is taken back."""
        view = memoryview(data)
        try:
            while view:
                view = view[os.write(self._fd, view) :]
            os.fsync(self._fd)
        except BaseException as error:
            if view:
                with contextlib.suppress(OSError):
                    os.ftruncate(self._fd, self._size)
            if isinstance(error, OSError):
                raise _unwritable(self.path, error) from None
            raise
        self._size += len(data)


@dataclass(frozen=True)
class _Record:
    """One CSV record of a file: its first line, its bytes, its fields, and whether a newline
    ends it (the last one of a file cut short does not)."""

    line: int
    start: int
    end: int
    fields: list[str]
    complete: bool
    lines: int

    @property
    def cut_short(self) -> bool:
        """The last row, cut while it was written: rows have no newlines in them, so a record
        open over several lines is damaged, not cut (dropping it would drop rows)."""
        return not self.complete and self.lines == 1


def _records(handle: BinaryIO, path: Path) -> Iterator[_Record]:
    """The file's CSV records with where each lies (for dropping a cut row, and sorting rows
    by copying their bytes)."""
    position = line = 0
    ended = True

    def lines() -> Iterator[str]:
        nonlocal position, line, ended
        for raw in handle:
            position, line, ended = position + len(raw), line + 1, raw.endswith(b"\n")
            try:
                yield raw.decode("utf-8")
            except UnicodeDecodeError:
                if ended:
                    raise InputError(f"{path}: line {line} is not text") from None
                yield ""  # a last line cut inside a character

    start, first = 0, 1
    for fields in csv.reader(lines()):
        yield _Record(first, start, position, fields, ended, line - first + 1)
        start, first = position, line + 1


def _scan(handle: BinaryIO, path: Path) -> tuple[_Record, Iterator[_Record]] | None:
    """The header and the rows of a results file; None for any other file."""
    if handle.read(len(START)) != START:
        return None
    handle.seek(0)
    records = _records(handle, path)
    header = next(records)
    if not header.complete or not set(header.fields) >= MARKS:
        return None
    return header, records


def _same_settings(path: Path, header: list[str], settings: list[str]) -> None:
    """Refuse to add rows under a header of other settings (the sweep file gained or lost a
    key since): its columns would not line up."""
    had = [column for column in header if column.startswith("config.")]
    if had == settings:
        return
    added = [name.removeprefix("config.") for name in settings if name not in had]
    lost = [name.removeprefix("config.") for name in had if name not in settings]
    changes = []
    if added:
        changes.append(f"this sweep adds {', '.join(added)}")
    if lost:
        changes.append(f"it had {', '.join(lost)}")
    change = "; ".join(changes)
    raise InputError(
        f"{path}: its rows come from a sweep with other settings ({change}); write to a new "
        "--out, or add --force to start it over"
    )


def _damage(header: list[str], record: _Record) -> str | None:
    """What is wrong with a row, if anything: a field too many or too few, or a run key that
    is not the run its settings columns name. A damaged row is refused, never skipped: its run
    would be missing from the results (or another run's taken for it) without a word."""
    fields = record.fields
    if not record.complete or len(fields) != len(header):
        return f"line {record.line} is damaged ({len(fields)} fields for {len(header)} columns)"
    run = _run(fields[0])
    settings = {name: field for name, field in zip(header, fields, strict=True)
                if name.startswith("config.")}  # fmt: skip
    if run is None or {f"config.{name}": _cell(value) for name, value in run.items()} != settings:
        return f"line {record.line} is damaged (its run key does not match its settings)"
    return None


def _run(key: str) -> dict[str, Any] | None:
    """A run's settings from its key; None for text that is no run key."""
    try:
        run = json.loads(key)
    except (ValueError, RecursionError):  # past 4,300 digits int() raises a plain ValueError
        return None
    return run if isinstance(run, dict) else None


def _cell(value: Any) -> str:
    """How a setting's value reads in its CSV column (as `csv.writer` writes it)."""
    return "" if value is None else str(value)


def _unlike(key: str, runs: Collection[str]) -> str:
    """What sets a run apart from `runs`: its first setting with a value none of them has."""
    run = _run(key) or {}
    values: dict[str, set[str]] = {}
    for other in runs:
        for name, value in (_run(other) or {}).items():
            values.setdefault(name, set()).add(json.dumps(value))
    for name, value in sorted(run.items()):
        if json.dumps(value) not in values.get(name, set()):
            return f"{name} {value}"
    return "another combination of its settings"


def _order(run: str) -> tuple:
    """Where a run's row goes: by shape, strategy, robots, the other settings, then seed."""
    config = json.loads(run)
    names = sorted(config, key=lambda name: (name == "seed", FIRST.get(name, len(FIRST)), name))
    return tuple(_value_order(config[name]) for name in names)


def _value_order(value: Any) -> tuple:
    """Numbers before text, each in its own order (135 after 45); anything else last."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        return (2, json.dumps(value))
    return (isinstance(value, str), value)


def _unwritable(path: Path, error: OSError) -> InputError:
    return InputError(
        f"{path}: cannot write to it ({error.strerror}); what it holds is unharmed, run the sweep "
        "again to go on"
    )


@contextlib.contextmanager
def _lock(path: Path) -> Iterator[None]:
    """Hold the lock file beside `path`, or refuse when another sweep holds it. The lock file
    is removed at the end (one left by a killed sweep is unlocked, and taken over)."""
    try:
        import fcntl
    except ImportError:  # Windows
        message = "sweeps need Linux or macOS: their results file is locked with flock"
        raise InputError(message) from None
    real = path.resolve()  # one lock for the file, whichever link names it
    lock = real.with_name(f".{real.name}.lock")
    while True:
        try:
            handle = lock.open("a")
        except OSError as error:
            raise InputError(f"{path}: cannot lock it ({error.strerror})") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            handle.close()
            if isinstance(error, BlockingIOError):
                raise InputError(
                    f"{path}: another sweep is writing to it; let it finish, or choose "
                    "another --out"
                ) from None
            raise InputError(f"{path}: cannot lock it ({error.strerror})") from None
        with contextlib.suppress(FileNotFoundError):
            if os.path.samestat(os.fstat(handle.fileno()), os.stat(lock)):
                break
        handle.close()  # the sweep before removed it between our open and our lock
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)
        handle.close()


def read_rows(path: Path) -> list[dict[str, str]]:
    """Every row of a results file, each whole; one clear error for anything else."""
    path = Path(path)
    with _reading(path) as handle:
        scanned = _scan(handle, path)
        if scanned is None:
            empty = " (it is empty)" if path.stat().st_size == 0 else ""
            raise InputError(f"{path}: not a swarmshape sweep CSV{empty}")
        header, records = scanned
        rows = []
        for record in records:
            if record.cut_short:
                raise InputError(
                    f"{path}: line {record.line} is cut short (its sweep was stopped while "
                    "writing it, or still is); run the sweep again to repair the file"
                )
            damage = _damage(header.fields, record)
            if damage:
                raise InputError(f"{path}: {damage}")
            rows.append(dict(zip(header.fields, record.fields, strict=True)))
    return rows


def _reading(path: Path) -> BinaryIO:
    """`path` open for reading, if it is a regular file: a pipe would hang the reader."""
    readable_file(path, "a sweep's results CSV")
    try:
        return path.open("rb")
    except OSError as error:
        raise InputError(f"{path}: cannot read it ({error.strerror})") from None


def _csv_text(lines: Iterable[list]) -> str:
    buffer = StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(lines)
    return buffer.getvalue()

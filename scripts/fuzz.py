"""A long fuzz of the command line and every file it reads, for humans (not part of the suite).

    .venv/bin/python scripts/fuzz.py --cases 10000 --seed 1 --minutes 120 --jobs 2

Draws cases as ``tests/test_fuzz.py`` does (see ``tests/fuzzing.py``), pipes and devices
included, and runs each in a forked process with its memory and time limited. Every distinct
failure is reported once with how often it came, the exception of any crash, and two ways to
reproduce it: the command in a kept folder, and ``--replay N`` with the same seed, which makes
the case afresh and runs it in a real ``swarmshape`` process. Nothing stops at the first.
"""

from __future__ import annotations

import argparse
import collections
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

from tests import fuzzing  # noqa: E402


class Draw:
    """`fuzzing.Pick` over a seeded generator: case N of seed S is the same on every run."""

    def __init__(self, seed: int, index: int) -> None:
        self.random = random.Random(f"{seed}:{index}")

    def integer(self, low: int, high: int) -> int:
        return self.random.randint(low, high)

    def choice(self, options):
        return self.random.choice(options)


@dataclass
class Failure:
    """One distinct way of failing, and the cases that failed so."""

    problem: str
    status: int | None
    line: str
    crash: str
    command: str
    cases: list[int] = field(default_factory=list)
    kinds: collections.Counter = field(default_factory=collections.Counter)


@dataclass
class Tally:
    """What the cases did: how many of each kind and status, and every
    distinct failure with a pristine copy of its first case kept for a human."""

    seed: int
    kinds: list[str]
    material: Path
    keep: Path
    ran: collections.Counter = field(default_factory=collections.Counter)
    statuses: collections.Counter = field(default_factory=collections.Counter)
    failures: dict[tuple, Failure] = field(default_factory=dict)

    def add(self, number: int, case: fuzzing.Case, outcome: fuzzing.Outcome, found: list) -> None:
        self.ran[case.kind] += 1
        self.statuses[outcome.status] += 1
        if not found:
            return
        where = fuzzing.crash(outcome)
        crash = f"{where[1]} (in {where[0]})" if where else ""
        key = signature(found[0], outcome, crash, case.folder)
        if key not in self.failures:
            kept = make(self.seed, number, self.kinds, self.material, self.keep / f"case-{number}")
            line = fuzzing.first_error_line(outcome)
            self.failures[key] = Failure(found[0], outcome.status, line, crash, kept.command())
            print(f"case {number} ({case.kind}): {found[0]} {crash}", flush=True)
        self.failures[key].cases.append(number)
        self.failures[key].kinds[case.kind] += 1

    def report(self, minutes: float, kinds_option: str | None) -> None:
        print(f"\n{sum(self.ran.values())} cases in {minutes:.1f} minutes, seed {self.seed}")
        for kind, count in self.ran.most_common():
            print(f"  {count:6}  {kind}")
        statuses = sorted(self.statuses.items(), key=str)
        print("exit statuses: " + ", ".join(f"{s}: {n}" for s, n in statuses))
        print(f"{len(self.failures)} distinct failures")
        for failure in sorted(self.failures.values(), key=lambda f: -len(f.cases)):
            kinds = ", ".join(f"{k} {n}" for k, n in failure.kinds.most_common())
            print(f"\n- {failure.problem} (exit status {failure.status}), "
                  f"{len(failure.cases)} cases: {kinds}")  # fmt: skip
            print(f"  stderr: {failure.line}")
            if failure.crash:
                print(f"  crash:  {failure.crash}")
            print(f"  again:  {failure.command}")
            only = f" --kinds {kinds_option}" if kinds_option else ""
            replay = f"--seed {self.seed} --replay {failure.cases[0]}{only}"
            print(f"  replay: .venv/bin/python scripts/fuzz.py {replay}")


def make(seed: int, index: int, kinds: list[str], material: Path, folder: Path) -> fuzzing.Case:
    """Case `index` of `seed`, made in `folder`: the same case every time."""
    draw = Draw(seed, index)
    return fuzzing.make_case(draw, draw.choice(kinds), material, folder, isolated=True)


def signature(problem: str, outcome: fuzzing.Outcome, crash: str, folder: Path) -> tuple:
    """What tells failures apart: the problem, the status, and where a crash happened or else
    the first line on stderr, without the case's own paths and numbers."""
    text = crash or fuzzing.first_error_line(outcome)
    text = text.replace(str(folder), "DIR")
    text = re.sub(r"[-\w.]*(nope|gone|pipe|out|link|target|loop|frames|nowhere)-\d+", "NAME", text)
    return (re.sub(r"\d+", "N", problem.split(":")[0]), outcome.status, re.sub(r"\d+", "N", text))


def run_process(case: fuzzing.Case) -> fuzzing.Outcome:
    """`case` in a real swarmshape process, cut short as its `fuzzing.Ending` says (a file size
    limit, SIGTERM after some seconds), as the fuzz's forked copy runs it."""
    ending = case.ending

    def limit_files() -> None:  # in the child, before swarmshape starts
        if ending.file_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (ending.file_limit,) * 2)

    started = time.perf_counter()
    with subprocess.Popen(
        [sys.executable, "-m", "swarmshape", *case.argv], cwd=case.folder, text=True,
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        preexec_fn=limit_files, start_new_session=True,
    ) as process:  # fmt: skip
        stop = ending.stop_after
        try:
            out, err = process.communicate(timeout=fuzzing.TIMEOUT if stop is None else stop)
        except subprocess.TimeoutExpired:  # hung, or due to be stopped
            if stop is not None:
                process.send_signal(signal.SIGTERM)
            try:
                out, err = process.communicate(timeout=0 if stop is None else fuzzing.TIMEOUT)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.communicate()
                return fuzzing.Outcome(None, "", "", time.perf_counter() - started)
    return fuzzing.Outcome(process.returncode, out, err, time.perf_counter() - started)


def replay(seed: int, index: int, kinds: list[str], material: Path, work: Path) -> int:
    """Make case `index` afresh and run it in a real swarmshape process; print what happened."""
    case = make(seed, index, kinds, material, work / f"case-{index}")
    named = fuzzing.Named(case)
    before = fuzzing.snapshot(case.folder)
    print(case.command())
    outcome = run_process(case)
    print(f"exit status {outcome.status}\n--- stdout\n{outcome.stdout}--- stderr\n{outcome.stderr}")
    found = fuzzing.problems(named, outcome, before, fuzzing.snapshot(case.folder))
    print("problems: " + ("; ".join(found) if found else "none"))
    return 1 if found else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=1000, help="cases to run (default 1000)")
    parser.add_argument("--seed", type=int, help="seed of the cases (default: a fresh one)")
    parser.add_argument("--minutes", type=float, help="stop after this long, whatever --cases")
    parser.add_argument("--jobs", type=int, default=1, help="cases at a time (default 1)")
    parser.add_argument("--kinds", help=f"comma-separated, of: {', '.join(fuzzing.KINDS)}")
    parser.add_argument("--timeout", type=float, default=fuzzing.TIMEOUT, help="seconds a case")
    parser.add_argument("--keep", type=Path, help="folder for failing cases (default: a new one)")
    parser.add_argument("--replay", type=int, metavar="N", help="run case N of --seed again")
    args = parser.parse_args()
    kinds = args.kinds.split(",") if args.kinds else list(fuzzing.KINDS)
    unknown = set(kinds) - set(fuzzing.KINDS)
    if unknown:
        parser.error(f"unknown kind {sorted(unknown)[0]!r}")
    seed = args.seed if args.seed is not None else random.randrange(2**32)
    keep = args.keep or Path(tempfile.mkdtemp(prefix="swarmshape-fuzz-"))
    keep.mkdir(parents=True, exist_ok=True)
    material = fuzzing.make_material(keep / "material")
    if args.replay is not None:
        if args.seed is None:
            parser.error("--replay needs the --seed of the fuzz that found the case")
        return replay(seed, args.replay, kinds, material, Path(tempfile.mkdtemp(dir=keep)))
    work = Path(tempfile.mkdtemp(prefix="cases-", dir=keep))
    logs = Path(tempfile.mkdtemp(prefix="logs-", dir=keep))
    print(f"seed {seed}; failing cases are kept in {keep}", flush=True)
    deadline = time.monotonic() + 60 * args.minutes if args.minutes else None
    tally = Tally(seed, kinds, material, keep)
    running: dict[int, tuple] = {}
    index = 0
    started = last_report = time.monotonic()

    def more() -> bool:
        return index < args.cases and (deadline is None or time.monotonic() < deadline)

    while running or more():
        while len(running) < args.jobs and more():
            case = make(seed, index, kinds, material, work / f"case-{index}")
            named, before = fuzzing.Named(case), fuzzing.snapshot(case.folder)
            running[index] = (case, named, before, fuzzing.Forked(case, args.timeout, logs))
            index += 1
        for number, (case, named, before, forked) in list(running.items()):
            outcome = forked.poll()
            if outcome is None:
                continue
            del running[number]
            found = fuzzing.problems(named, outcome, before, fuzzing.snapshot(case.folder))
            tally.add(number, case, outcome, found)
            shutil.rmtree(case.folder, ignore_errors=True)
        if time.monotonic() - last_report > 60:
            last_report = time.monotonic()
            total = sum(tally.ran.values())
            print(f"{total} cases, {len(tally.failures)} distinct failures, "
                  f"{total / (last_report - started):.1f} cases/s", flush=True)  # fmt: skip
        time.sleep(0.002)
    shutil.rmtree(work, ignore_errors=True)
    tally.report((time.monotonic() - started) / 60, args.kinds)
    return 1 if tally.failures else 0


if __name__ == "__main__":
    sys.exit(main())

"""Runs command lines for the tests (`tests.conftest.python`), each in a child forked from
this process, which has imported swarmshape and loaded its compiled kernels once: a fresh
interpreter would spend 0.3 s on that for each of the suite's 150-odd command lines.

Reads one request a line on stdin (JSON: args, cwd, env, out, err, timeout); answers, when the
child has ended or been killed at the timeout, with its exit code as `subprocess` gives it (-N
for signal N) and whether it timed out. What a child cannot have as a fresh interpreter has
it (its own hash seed, the environment's ``PYTHON*`` start-up settings) is `conftest`'s to
route to a real one.
"""

from __future__ import annotations

import atexit
import contextlib
import io
import json
import os
import runpy
import select
import signal
import sys
import threading
import time
import traceback
import warnings
from pathlib import Path

from swarmshape.cli import main

STARTING_PATH = [
    path
    for path in sys.path[1:]  # not this script's folder
    if path not in os.environ.get("PYTHONPATH", "").split(os.pathsep)
]
"""The module path a fresh interpreter starts from, before its folder and PYTHONPATH."""


def warm_up() -> None:
    """Load what a command's first step loads (numba and the kernels), quietly, leaving the
    warnings as they were (a command sets how they are shown)."""
    line = Path(__file__).resolve().parent.parent / "shapes" / "line.png"
    with contextlib.ExitStack() as stack:
        stack.enter_context(warnings.catch_warnings())
        stack.enter_context(contextlib.redirect_stdout(io.StringIO()))
        stack.enter_context(contextlib.redirect_stderr(io.StringIO()))
        main([str(line), "--headless", "--max-steps", "3"])


def run_as_python(args: list[str], cwd: str, env: dict, out: str, err: str) -> int:
    """In the child: the folder, environment, streams and module path that ``python ARGS``
    has, then its module (``-m``) or script as ``__main__``, and its exit as a fresh
    interpreter's: threads joined, exit functions run; its exit code."""
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    first = cwd if args[0] == "-m" else str(Path(args[0]).resolve().parent)
    extra = [path for path in env.get("PYTHONPATH", "").split(os.pathsep) if path]
    sys.path[:] = [first, *extra, *STARTING_PATH]
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    for fd, path in ((1, out), (2, err)):
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
    sys.stdin = open(0, closefd=False)  # noqa: SIM115
    stdout, stderr = sys.__stdout__, sys.__stderr__  # pipes, as a fresh interpreter's are
    sys.stdout = open(1, "w", encoding=stdout.encoding, errors=stdout.errors, closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", encoding=stderr.encoding, errors=stderr.errors, closefd=False)  # noqa: SIM115
    try:
        if args[0] == "-m":
            sys.argv = args[1:]
            runpy.run_module(args[1], run_name="__main__", alter_sys=True)
        else:
            sys.argv = [os.path.abspath(args[0]), *args[1:]]
            runpy.run_path(sys.argv[0], run_name="__main__")
        code = 0
    except SystemExit as stop:
        code = stop.code if isinstance(stop.code, int) else 0 if stop.code is None else 1
        if not isinstance(stop.code, int | None):
            print(stop.code, file=sys.stderr)
    except KeyboardInterrupt:  # a fresh interpreter ends by the signal
        traceback.print_exc()
        code = -signal.SIGINT
    except BaseException:
        traceback.print_exc()
        code = 1
    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon:
            thread.join()
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    if code == -signal.SIGINT:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    return code


def serve() -> None:
    warm_up()
    for line in sys.stdin:
        request = json.loads(line)
        timeout = request.pop("timeout")
        child = os.fork()
        if child == 0:
            os._exit(run_as_python(**request))
        timed_out = not ends_within(child, timeout)
        if timed_out:
            os.kill(child, signal.SIGKILL)
        _, status = os.waitpid(child, 0)
        code = os.waitstatus_to_exitcode(status)
        print(json.dumps({"code": code, "timed_out": timed_out}), flush=True)


def ends_within(child: int, timeout: float) -> bool:
    """Whether process `child` ends within `timeout` seconds (left to be reaped). Where a
    sandbox refuses pidfd_open, by asking every few milliseconds."""
    try:
        ended = os.pidfd_open(child)
    except OSError:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if os.waitid(os.P_PID, child, os.WEXITED | os.WNOHANG | os.WNOWAIT):
                return True
            time.sleep(0.005)
        return False
    try:
        return bool(select.select([ended], [], [], timeout)[0])
    finally:
        os.close(ended)


if __name__ == "__main__":
    serve()

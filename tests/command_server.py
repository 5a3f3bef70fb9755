"""Runs command lines for the tests (`tests.conftest.python`), each in a child forked from
this process, which has imported swarmshape and loaded its compiled kernels once: a fresh
interpreter would spend 0.3 s on that for each of the suite's few hundred command lines.

Reads one request a line on stdin (JSON: args, cwd, env, out, err, timeout); answers, when the
child has ended or been killed at the timeout, with its exit code as `subprocess` gives it (-N
for signal N) and whether it timed out.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import runpy
import select
import signal
import sys
import traceback
from pathlib import Path

from swarmshape.cli import main


def warm_up() -> None:
    """Load what a command's first step loads (numba and the kernels), quietly."""
    line = Path(__file__).resolve().parent.parent / "shapes" / "line.png"
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        main([str(line), "--headless", "--max-steps", "3"])


def run_as_python(args: list[str], cwd: str, env: dict, out: str, err: str) -> int:
    """In the child: the folder, environment, streams and module path that ``python ARGS``
    has, then its module (``-m``) or script as ``__main__``; its exit code."""
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    sys.path[:0] = [path for path in env.get("PYTHONPATH", "").split(os.pathsep) if path]
    for fd, path in ((1, out), (2, err)):
        os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
    sys.stdout = open(1, "w", encoding="utf-8", closefd=False)  # noqa: SIM115
    sys.stderr = open(2, "w", encoding="utf-8", errors="backslashreplace", closefd=False)  # noqa: SIM115
    sys.argv = list(args)
    try:
        if args[0] == "-m":  # on the path first: the working folder, or the script's
            sys.argv.pop(0)
            sys.path.insert(0, cwd)
            runpy.run_module(args[1], run_name="__main__", alter_sys=True)
        else:
            sys.path.insert(0, str(Path(args[0]).resolve().parent))
            runpy.run_path(args[0], run_name="__main__")
        return 0
    except SystemExit as stop:
        if stop.code is None or isinstance(stop.code, int):
            return stop.code or 0
        print(stop.code, file=sys.stderr)
        return 1
    except BaseException:
        traceback.print_exc()
        return 1
    finally:
        sys.stdout.flush()
        sys.stderr.flush()


def serve() -> None:
    warm_up()
    for line in sys.stdin:
        request = json.loads(line)
        timeout = request.pop("timeout")
        child = os.fork()
        if child == 0:
            sys.stdin.close()
            os._exit(run_as_python(**request))
        ended = os.pidfd_open(child)
        timed_out = not select.select([ended], [], [], timeout)[0]
        if timed_out:
            os.kill(child, signal.SIGKILL)
        os.close(ended)
        _, status = os.waitpid(child, 0)
        code = os.waitstatus_to_exitcode(status)
        print(json.dumps({"code": code, "timed_out": timed_out}), flush=True)


if __name__ == "__main__":
    serve()

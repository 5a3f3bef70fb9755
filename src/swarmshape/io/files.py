"""Files in and out, so that a crash, a full disk or an odd path never loses a user's work.

Inputs must be regular files (a pipe would hang the read). Outputs are checked before a run
starts and written to a temporary file beside their target, then renamed over it in one step;
a symlink is written through to the file it points to. A failure to write is one line, like
any other bad input.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
import tomllib
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from swarmshape.errors import InputError

TEMP_PREFIX = ".swarmshape-"
"""Temporary files start with this, then the process id (hidden, and short, so any legal name
still fits)."""

_folders: set[Path] = set()
"""Every folder this process has made a temporary in, noted before it is made."""


def _temporary_prefix(folder: Path) -> str:
    """The prefix of this process's temporaries, `folder` noted first: a signal that strikes
    between making a temporary and taking it into a cleanup finds it all the same
    (`remove_temporaries`)."""
    _folders.add(folder)
    return f"{TEMP_PREFIX}{os.getpid()}-"


def remove_temporaries() -> None:
    """Remove whatever temporaries this process made and did not rename: called as a command
    ends, however it ends. A run sent SIGTERM just as it made its frames' folder left it behind
    (the fuzz, 2 of 330 signalled runs): the signal struck before the folder was the run's to
    discard."""
    for folder in _folders:
        for path in folder.glob(f"{TEMP_PREFIX}{os.getpid()}-*"):
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)


class OutputError(InputError):
    """An output that cannot be written; the message names it and says why."""


def atomic_write(path: str | os.PathLike[str], write: Callable[[str], object]) -> None:
    """Call ``write(temp_path)`` beside `path`, then rename it over `path` in one step.

    The temporary name keeps a short final suffix so that writers which pick a format from the
    extension (Pillow, pygame) still do. A symlink is written through to its target.
    """
    atomic_writes([(path, write)])


def atomic_writes(writes: Sequence[tuple[str | os.PathLike[str], Callable[[str], object]]]) -> None:
    """`atomic_write` for files that belong together (a set of plots): every one is written
    under its temporary name before any is renamed, so that a failure (a full disk) leaves
    all of them as they were, not some new beside some old."""
    done: list[tuple[str, Path]] = []
    try:
        for given, write in writes:
            path = Path(os.path.realpath(given))
            try:
                prefix, suffix = _temporary_prefix(path.parent), path.suffix[-16:]
                fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=prefix, suffix=suffix)
            except OSError as error:
                raise OutputError(f"{path}: cannot write there ({error.strerror})") from None
            os.close(fd)
            done.append((tmp, path))
            try:
                write(tmp)
                os.chmod(tmp, _mode_for(path))  # mkstemp makes it private
            except OSError as error:
                raise OutputError(f"{path}: cannot write it ({error.strerror or error})") from None
        for tmp, path in done:
            try:
                os.replace(tmp, path)
            except OSError as error:
                raise OutputError(f"{path}: cannot write it ({error.strerror or error})") from None
    finally:
        for tmp, _ in done:
            Path(tmp).unlink(missing_ok=True)


class StreamedFile:
    """A text output written as a run goes (rows of a trace), kept under a temporary name
    beside its target and renamed over it at `commit`; `discard` leaves nothing behind."""

    def __init__(self, path: Path) -> None:
        self.path = Path(os.path.realpath(path))
        try:
            prefix = _temporary_prefix(self.path.parent)
            fd, self._tmp = tempfile.mkstemp(dir=self.path.parent, prefix=prefix)
        except OSError as error:
            raise OutputError(f"{path}: cannot write there ({error.strerror})") from None
        self.handle = os.fdopen(fd, "w", newline="", encoding="utf-8")

    def commit(self) -> None:
        try:
            self.handle.close()
            os.chmod(self._tmp, _mode_for(self.path))
            os.replace(self._tmp, self.path)
        except OSError as error:
            self.discard()
            raise OutputError(f"{self.path}: cannot write it ({error.strerror})") from None

    def failed(self, error: OSError) -> OutputError:
        """Give up after a failed write: remove the partial file, and say why in one line."""
        self.discard()
        return OutputError(f"{self.path}: cannot write it ({error.strerror or error})")

    def discard(self) -> None:
        """Remove the temporary file; what could not be written is dropped (a full disk fails
        the flush of the last rows as well), and a second call does nothing."""
        with contextlib.suppress(OSError):
            self.handle.close()
        Path(self._tmp).unlink(missing_ok=True)


class TemporaryFolder:
    """Files written one by one as a run goes (numbered frames), kept in a temporary folder
    beside `target` and moved into it at `finish`; `discard` leaves nothing behind."""

    def __init__(self, target: Path) -> None:
        self.target = target
        try:
            prefix = _temporary_prefix(target.parent)
            self.path = Path(tempfile.mkdtemp(dir=target.parent, prefix=prefix))
        except OSError as error:
            raise OutputError(f"{target}: cannot write there ({error.strerror})") from None

    def finish(self, replaces: str) -> None:
        """Move the files in: the whole folder if `target` is not there yet, else file by file,
        and then remove the files of the target matching the pattern `replaces` that this
        run did not write (an earlier run's)."""
        try:
            if not self.target.exists():
                os.chmod(self.path, 0o777 & ~umask())  # mkdtemp makes it private
                os.replace(self.path, self.target)
                return
            written = {path.name for path in self.path.iterdir()}
            for name in sorted(written):
                os.replace(self.path / name, self.target / name)
            for stale in self.target.glob(replaces):
                if stale.name not in written:
                    stale.unlink()
            self.path.rmdir()
        except OSError as error:
            self.discard()
            raise OutputError(f"{self.target}: cannot write it ({error.strerror})") from None

    def discard(self) -> None:
        shutil.rmtree(self.path, ignore_errors=True)


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Atomically write `text` (UTF-8)."""
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def readable_file(path: Path, expected: str, error: type[InputError] = InputError) -> Path:
    """`path` if it is a regular file (a symlink counts as what it points to); a folder, a pipe,
    a device or a missing file is refused in one line (an `error`) before anything reads it.
    `expected` says what it should be, e.g. "an image"."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except OSError as failure:
        raise error(f"{path}: cannot read it ({failure.strerror})") from None
    except ValueError:  # no file name may hold a NUL byte
        raise error(f"{path}: no such file (its name holds a NUL byte)") from None
    if stat.S_ISDIR(mode):
        raise error(f"{path}: is a directory, expected {expected}")
    if not stat.S_ISREG(mode):
        raise error(f"{path}: is not a regular file (a pipe or a device?), expected {expected}")
    return path


def read_toml(path: Path, expected: str, error: type[InputError] = InputError) -> dict[str, Any]:
    """The table of the TOML file `path` (`expected`, e.g. "a .toml scenario"), read only if it
    is a regular file (`readable_file`); whatever is wrong with it is one line (an `error`)."""
    readable_file(path, expected, error)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as failure:
        raise error(f"{path}: cannot read it ({failure.strerror})") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as failure:
        raise error(f"{path}: not valid TOML ({failure})") from None
    except ValueError:  # tomllib reads integers with int(), which stops at 4,300 digits
        raise error(f"{path}: holds a number of more than 4,300 digits") from None
    except RecursionError:  # tomllib recurses once per level of nesting
        raise error(f"{path}: nested too deeply to be {expected}") from None


def not_standard_output(path: Path, flag: str, what: str = "a file") -> None:
    """Refuse ``-`` as an output's name: to most tools it means standard output, and taken
    as a name it made a file (or folder) named ``-`` where the user looked for none."""
    if os.fspath(path) == "-":
        raise OutputError(f"-: {flag} writes {what}, not standard output; name {what}")


def check_output(
    path: Path,
    flag: str,
    *,
    may_replace: bool,
    folder: bool = False,
    inputs: Mapping[Path, str] | None = None,
) -> None:
    """Refuse, before a run, an output that cannot be written there, that is not a regular file
    (or, for a `folder` output, a folder), that is one of the run's `inputs` (path: what it is
    to the run; told apart by `identity`,
    whatever `may_replace` says: a run never writes over what it reads), or that would replace
    an existing file (or fill a non-empty folder) without `may_replace`. A symlink counts as the
    file it points to. ``-`` is refused too (`not_standard_output`)."""
    not_standard_output(path, flag)
    target = Path(os.path.realpath(path))
    if os.path.islink(target):  # realpath stops at a link it cannot resolve: a loop
        raise OutputError(f"{path}: {flag} names a symlink that leads back to itself; name a file")
    nowhere = OutputError(f"{path}: {flag} cannot write there (no such folder, or no permission)")
    try:
        longest = os.pathconf(target.parent, "PC_NAME_MAX")
    except OSError:
        raise nowhere from None
    if len(target.name.encode()) > longest:  # first: such a name cannot even be looked up
        raise OutputError(f"{path}: {flag} name is longer than the {longest} bytes allowed")
    existing = target if folder and target.is_dir() else target.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise nowhere
    if target.exists():
        mode = target.stat().st_mode
        if folder and not stat.S_ISDIR(mode):
            raise OutputError(f"{path}: {flag} needs a folder, and this is not one")
        if not folder and stat.S_ISDIR(mode):
            raise OutputError(f"{path}: {flag} needs a file name, and this is a folder")
        if not folder and not stat.S_ISREG(mode):
            raise OutputError(f"{path}: {flag} would replace a pipe or a device; name a file")
        read = {identity(file): what for file, what in (inputs or {}).items()}
        read.pop(None, None)  # an input not there (yet) is no file to keep
        what = read.get(identity(target))
        if what is not None:
            raise OutputError(f"{path}: {flag} would replace {what}; name another file")
        if not may_replace and (not folder or any(target.iterdir())):
            raise OutputError(f"{path}: {flag} would overwrite it; add --force to allow that")


def identity(path: str | os.PathLike[str]) -> tuple[int, int] | None:
    """What tells files apart whatever their names (symlinks, hard links, ``..``): device and
    inode; None for a file that is not there or cannot be looked up."""
    try:
        info = os.stat(path)
    except (OSError, ValueError):  # ValueError: a NUL byte in the name
        return None
    return info.st_dev, info.st_ino


def distinct_outputs(outputs: Iterable[tuple[str, Path]]) -> None:
    """Refuse two options naming the same file: one would silently overwrite the other."""
    seen: dict[str, str] = {}
    for flag, path in outputs:
        key = os.path.realpath(path)
        if key in seen:
            raise OutputError(f"{path}: {seen[key]} and {flag} both write it; name two files")
        seen[key] = flag


def _mode_for(path: Path) -> int:
    """The permission bits a file written to `path` gets: those of the file it replaces, or
    the umask's for a new one."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return 0o666 & ~umask()


def umask() -> int:
    """The process umask (reading it means setting it, so it is set straight back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask

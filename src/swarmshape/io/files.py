"""Writing files so that a crash or a full disk never leaves a user's file half-written."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from swarmshape.errors import InputError


def atomic_write(path: str | os.PathLike[str], write: Callable[[str], object]) -> None:
    """Call ``write(temp_path)`` beside `path`, then rename it over `path` in one step.

    The temporary name keeps the final suffix so that writers which pick a format from the
    extension (Pillow, pygame) still do.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~umask())  # mkstemp makes it private; give it the usual mode
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def check_output(path: Path, flag: str, *, may_replace: bool) -> None:
    """Refuse, before a run, an output that cannot be written there or that would replace an
    existing file (or fill a non-empty folder, for ``--frames``) without `may_replace`."""
    folder_output = flag == "--frames"
    replaces = path.is_file() or (folder_output and path.is_dir() and any(path.iterdir()))
    if replaces and not may_replace:
        raise InputError(f"{path}: {flag} would overwrite it; add --force to allow that")
    if not folder_output and path.is_dir():
        raise InputError(f"{path}: {flag} needs a file name, and this is a folder")
    # a file goes into an existing folder; the frames folder may be made, inside one
    existing = path if folder_output and path.is_dir() else path.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise InputError(f"{path}: {flag} cannot write there (no such folder, or no permission)")


def write_text(path: str | os.PathLike[str], text: str) -> None:
    """Atomically write `text` (UTF-8)."""
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def umask() -> int:
    """The process umask (reading it means setting it, so it is set straight back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask

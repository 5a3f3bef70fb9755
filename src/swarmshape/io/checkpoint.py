"""Saved runs on disk: numpy arrays and a JSON manifest in one ``.npz`` file, with no code in it.

The manifest names the format and its version, holds every plain value, lists the arrays, and
carries a SHA-256 over all of it, so a damaged file is refused rather than resumed differently.
Arrays are read with ``allow_pickle=False`` and the whole file is size-checked before anything
is decompressed, so a crafted file can neither run code nor exhaust memory.
"""

from __future__ import annotations

import hashlib
import json
import math
import zipfile
import zlib
from collections.abc import Mapping
from pathlib import Path
from tokenize import TokenError
from typing import Any

import numpy as np

from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write, readable_file

FORMAT = "swarmshape state"
VERSION = 4
"""4: a run keeps its plug-in's options and its senses; 3 kept the paper's order as a run
setting. 3: runs keep their faults (schedule, log, lost robots); 2 could not hold them."""
MANIFEST = "manifest"
MAX_BYTES = 8 * 2**30
"""Largest state, uncompressed: about what a million robots on the largest arena take."""
PICKLE_HEADER = b"swarmshape state 1\n"
"""How the first, pickle-based format began; such files are refused, never unpickled."""


def save_state(path: Path, values: Mapping[str, Any]) -> None:
    """Write `values` (arrays, and JSON numbers, text, lists, mappings) to `path` atomically."""
    arrays = {
        key: np.ascontiguousarray(v) for key, v in values.items() if isinstance(v, np.ndarray)
    }
    plain = {key: v for key, v in values.items() if not isinstance(v, np.ndarray)}
    manifest = {"format": FORMAT, "version": VERSION, "values": plain, "arrays": sorted(arrays)}
    manifest["checksum"] = _checksum(manifest, arrays)
    text = json.dumps(manifest, sort_keys=True, allow_nan=False).encode("utf-8")
    members = {MANIFEST: np.frombuffer(text, dtype=np.uint8), **arrays}

    def write(tmp: str) -> None:
        with open(tmp, "wb") as handle:
            np.savez_compressed(handle, **members)

    atomic_write(path, write)


def load_state(path: Path) -> dict[str, Any]:
    """The values a state file holds; anything else (not ours, damaged, too large) is refused
    with one line."""
    path = readable_file(Path(path), "a state file")
    with path.open("rb") as handle:
        start = handle.read(len(PICKLE_HEADER))
    if start == PICKLE_HEADER:
        raise InputError(
            f"{path}: a state file of an older swarmshape (pickle, which is unsafe to load); "
            "run it again and save it with this version"
        )
    try:
        with zipfile.ZipFile(path) as archive:
            names = {info.filename: info.file_size for info in archive.infolist()}
    except (zipfile.BadZipFile, OSError, ValueError, NotImplementedError):
        # zipfile refuses a damaged header's "version needed to extract" with NotImplementedError
        raise InputError(
            f"{path}: not a swarmshape state file (write one with --save-state)"
        ) from None
    if f"{MANIFEST}.npy" not in names:
        raise InputError(f"{path}: not a swarmshape state file (write one with --save-state)")
    if sum(names.values()) > MAX_BYTES:
        raise InputError(f"{path}: state file too large (over {MAX_BYTES // 2**30} GiB unpacked)")
    try:
        with np.load(path, allow_pickle=False) as archive:
            members = {name: archive[name] for name in archive.files}
        if not all(isinstance(member, np.ndarray) for member in members.values()):
            raise ValueError("a member that is not an array")  # numpy hands those over as bytes
        text = members.pop(MANIFEST).tobytes().decode("utf-8")
        manifest = json.loads(text, parse_float=_finite, parse_constant=_finite)
    except (ValueError, OSError, EOFError, KeyError, zipfile.BadZipFile, zlib.error, UnicodeError,
            RecursionError, TokenError, MemoryError, NotImplementedError):  # fmt: skip
        # numpy tokenizes a damaged array header (TokenError), and allocates what one declares;
        # zipfile meets compression methods it does not know (NotImplementedError)
        raise InputError(f"{path}: damaged state file (it cannot be read)") from None
    return _checked(path, manifest, members)


def _checked(path: Path, manifest: Any, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise InputError(f"{path}: not a swarmshape state file (write one with --save-state)")
    if manifest.get("version") != VERSION:
        raise InputError(
            f"{path}: a state file of format version {manifest.get('version')!r}; this "
            f"swarmshape reads version {VERSION}"
        )
    listed, plain = manifest.get("arrays"), manifest.get("values")
    if listed != sorted(arrays) or not isinstance(plain, dict):
        raise InputError(f"{path}: damaged state file (its parts do not match its list)")
    claimed = manifest.pop("checksum", None)
    if claimed != _checksum(manifest, arrays):
        raise InputError(f"{path}: damaged state file (its checksum does not match)")
    return {**plain, **arrays}


def _finite(text: str) -> float:
    """A number of the manifest; NaN and infinities (which `save_state` never writes, and
    its checksum cannot hold) mean a damaged file."""
    number = float(text)
    if not math.isfinite(number):
        raise ValueError(f"{text} is not a finite number")
    return number


def _checksum(manifest: Mapping[str, Any], arrays: Mapping[str, np.ndarray]) -> str:
    digest = hashlib.sha256(json.dumps(manifest, sort_keys=True, allow_nan=False).encode())
    for key in sorted(arrays):
        array = np.ascontiguousarray(arrays[key])
        digest.update(f"{key}|{array.dtype.str}|{array.shape}|".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()

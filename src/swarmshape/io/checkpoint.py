"""Saved runs on disk: numpy arrays and a JSON manifest in one ``.npz`` file, with no code in it.

The manifest names the format and its version, holds every plain value, lists the arrays, and
carries a SHA-256 over all of it, so a damaged file is refused rather than resumed differently.
Arrays are read with ``allow_pickle=False``. The manifest is read first (within
`MAX_MANIFEST`), then every array's header: each must declare the size its member unpacks to,
and together they must fit what a run of the world the manifest describes can keep
(`most_bytes`), before any array is decompressed; so a crafted file can neither run code nor
exhaust memory or time.
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
import numpy.lib.format as npy

from swarmshape.errors import InputError
from swarmshape.io.files import atomic_write, readable_file

FORMAT = "swarmshape state"
VERSION = 5
"""5: a run keeps what it does on losing robots (`on_loss`). 4: a run keeps its plug-in's
options and its senses; 3 kept the paper's order as a run setting. 3: runs keep their faults
(schedule, log, lost robots); 2 could not hold them."""
MANIFEST = "manifest"
MAX_BYTES = 8 * 2**30
"""Largest state, uncompressed: about what a million robots on the largest arena take."""
MAX_MANIFEST = 2**30
"""Largest manifest, uncompressed (a long fault log is its longest part)."""
ROBOT_BYTES = 4096
"""What a run keeps per robot, at most: its arrays (cells, speeds, states, targets ...) and a
program's memory, with room to spare (today's programs keep under 400 bytes)."""
CELL_BYTES = 64
"""What a run keeps per arena cell, at most, besides path fields: the lattice's holders and
queue, each group's grid (today 17 bytes a cell)."""
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
    if names[f"{MANIFEST}.npy"] > MAX_MANIFEST:
        raise InputError(f"{path}: state file too large (its manifest is over 1 GiB unpacked)")
    try:
        with np.load(path, allow_pickle=False) as archive:
            manifest = _manifest(archive[MANIFEST])
            declared = {name: _declared(archive.zip, name) for name in archive.zip.namelist()}
            declared.pop(f"{MANIFEST}.npy")
            most, total = most_bytes(manifest), sum(declared.values())
            if most is None and total:
                raise ValueError("arrays, and a manifest that does not say the size of its world")
            if total > (most or 0):
                raise StateTooLarge(total, most or 0)
            members = {name: archive[name] for name in archive.files if name != MANIFEST}
        if not all(isinstance(member, np.ndarray) for member in members.values()):
            raise ValueError("a member that is not an array")  # numpy hands those over as bytes
    except StateTooLarge as error:
        raise InputError(
            f"{path}: state file too large for its run ({error.declared:,} bytes unpacked, where "
            f"a run of its world keeps at most {error.most:,})"
        ) from None
    except (ValueError, OSError, EOFError, KeyError, zipfile.BadZipFile, zlib.error, UnicodeError,
            RecursionError, TokenError, MemoryError, NotImplementedError):  # fmt: skip
        # numpy tokenizes a damaged array header (TokenError), and allocates what one declares;
        # zipfile meets compression methods it does not know (NotImplementedError)
        raise InputError(f"{path}: damaged state file (it cannot be read)") from None
    return _checked(path, manifest, members)


class StateTooLarge(Exception):
    """Arrays that would unpack to more than their run can keep."""

    def __init__(self, declared: int, most: int) -> None:
        self.declared, self.most = declared, most


def _manifest(member: Any) -> Any:
    """The manifest's JSON, from its member (numpy hands a member that is no .npy over as
    bytes, which is a damaged file)."""
    if not isinstance(member, np.ndarray):
        raise ValueError("a manifest that is not an array")
    return json.loads(member.tobytes().decode("utf-8"), parse_float=_finite, parse_constant=_finite)


def _declared(archive: zipfile.ZipFile, name: str) -> int:
    """The bytes the member `name` unpacks to, read from its header alone (a few hundred
    bytes): the array it declares must be exactly what the member holds, or numpy would
    allocate what a header claims."""
    size = archive.getinfo(name).file_size
    with archive.open(name) as member:
        version = npy.read_magic(member)
        if version == (1, 0):
            shape, _, dtype = npy.read_array_header_1_0(member)
        elif version in ((2, 0), (3, 0)):
            shape, _, dtype = npy.read_array_header_2_0(member)
        else:
            raise ValueError(f"an array of npy format {version}")
        header = member.tell()
    if dtype.hasobject:
        raise ValueError("an array of Python objects")  # pickle, which is never loaded
    data = math.prod(shape) * dtype.itemsize
    if header + data != size:
        raise ValueError("an array header that does not match its member")
    return size


def most_bytes(manifest: Any) -> int | None:
    """The most a saved run of the world `manifest` describes can keep: per robot, per arena
    cell, and a path field (a float per cell) for every robot and as many again spare (the
    planner doubles its rows as it needs them); within `MAX_BYTES`. None if the manifest does
    not say its world's size and robots."""
    values = manifest.get("values") if isinstance(manifest, dict) else None
    values = values if isinstance(values, dict) else {}
    size, groups = values.get("swarm.world.size"), values.get("swarm.world.groups")
    if not (isinstance(size, list) and len(size) == 2 and all(_count(v) for v in size)):
        return None
    if not _count(groups):
        return None
    agents = [values.get(f"swarm.world.group{index}.agents") for index in range(groups)]
    if not all(_count(a) for a in agents):
        return None
    robots, cells = sum(agents), (size[0] + 2) * (size[1] + 2)
    fields = 8 * cells * (2 * robots + 4)
    return min(MAX_BYTES, ROBOT_BYTES * robots + CELL_BYTES * cells * groups + fields)


def _count(value: Any) -> bool:
    return type(value) is int and 0 <= value <= MAX_BYTES


def _checked(path: Path, manifest: Any, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise InputError(f"{path}: not a swarmshape state file (write one with --save-state)")
    version = manifest.get("version")
    if type(version) is not int:  # '3' would read "version '3'; this reads version 3"
        raise InputError(f"{path}: damaged state file (its format version is not a number)")
    if version != VERSION:
        raise InputError(
            f"{path}: a state file of format version {version}; this "
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

"""Keep the memory a step frees for the next step, so numpy's large temporaries are reused
rather than handed back to the system and faulted in again.

A step at 10,000 robots allocates and frees arrays of several MB dozens of times. glibc maps
a block over 128 KB afresh and unmaps it when freed, and hands back memory freed at the top of
its heap; it raises both thresholds by itself, but only once it has unmapped a block of up to
32 MB. Whether that happened early in a run varied from process to process (with the hash
seed, say): a process where it had not faulted 2,400 to 4,000 pages back in every step, 5 to
9 ms of `mean-shift`'s 30 ms step on the 10,000-robot S. Set where glibc raises them at most,
every process runs as the lucky ones did. Elsewhere (another C library, another system) this
does nothing, and so it does where the user set glibc's thresholds (`OWN_SETTINGS`): theirs
win, and setting them to glibc's defaults turns this off.
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys

M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
"""glibc's `mallopt` parameters (malloc.h)."""
MMAP_THRESHOLD = 32 << 20
"""The most glibc raises its mmap threshold to by itself on 64-bit systems; it then keeps
twice as much free at the top of its heap."""
OWN_SETTINGS = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")
"""The environment variables by which a user sets glibc's thresholds (as does
``GLIBC_TUNABLES=glibc.malloc.mmap_threshold=...``)."""


@functools.cache
def keep_freed_memory() -> None:
    """Set glibc's thresholds (once a process) as high as it raises them itself, unless the
    user set them."""
    tunables = os.environ.get("GLIBC_TUNABLES", "")
    if not sys.platform.startswith("linux") or any(map(os.environ.get, OWN_SETTINGS)):
        return
    if "glibc.malloc.mmap_threshold" in tunables or "glibc.malloc.trim_threshold" in tunables:
        return
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # no C library to ask, or one without mallopt
        return
    mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)
    mallopt(M_TRIM_THRESHOLD, 2 * MMAP_THRESHOLD)

"""News from beyond a robot's sensing range, passed on hop by hop.

A robot that sees something (an open cell of its shape, a seed) tells it at 0 hops; every
other robot takes the least count it hears, plus one, with what that neighbour told (a frame
cell, say). This is distributed Bellman-Ford: counts settle to the hops to the nearest source
one hop a step, and when a source goes away the counts near it rise, one a step, until they
reach the next source, or `cap` where there is none.

A count is broadcast as one more than itself, so that 0 means "no count": a robot's message
before it first speaks is all zeros (`said`, `heard`).
"""

from __future__ import annotations

import numpy as np

from swarmshape.core.compiled import njit
from swarmshape.core.perception import Perception

NONE = 1 << 30
"""A count never heard: more than any cap."""


def said(count: np.ndarray, cap: int) -> np.ndarray:
    """A count as broadcast: one more than itself, 0 for none (`cap` or more)."""
    return np.where(count < cap, count + 1, 0)


def heard(field: np.ndarray) -> np.ndarray:
    """A broadcast count as a count, `NONE` where none was said."""
    out = np.empty(field.shape, dtype=field.dtype)
    _heard(np.ravel(field), out.reshape(-1))
    return out


@njit
def _heard(field: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover (compiled)
    """`heard` in one pass: numpy's compare, subtract and choice over the 240,000 entries of
    the 10,000-robot S took 0.3 ms, five times a `mean-shift` step."""
    for i in range(len(field)):
        out[i] = field[i] - 1 if field[i] > 0 else NONE


def relay(
    sense: Perception,
    heard: np.ndarray,
    hops: np.ndarray,
    told: np.ndarray,
    source: np.ndarray,
    found: np.ndarray,
    cap: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Per robot, its hops to the nearest source and what that source told.

    Per entry: `heard` (the neighbour's message came through and is news to take), its `hops`
    and what it `told` ``(m, k)``. Per robot: whether it is a `source` itself and what it
    `found` ``(n, k)``. Counts stop at `cap` (no news)."""
    best = best_per_robot(len(sense), sense.owner, hops, heard & (hops < cap))
    return passed(best, hops, told, source, found, cap)


def passed(
    best: np.ndarray,
    hops: np.ndarray,
    told: np.ndarray,
    source: np.ndarray,
    found: np.ndarray,
    cap: int,
) -> tuple[np.ndarray, np.ndarray]:
    """`relay`'s counts and news from each robot's `best` entry (-1: none), for a program
    that picks it its own way."""
    has = best >= 0
    count = np.full(len(best), cap, dtype=np.int64)
    count[has] = np.minimum(hops[best[has]] + 1, cap)
    news = np.zeros_like(found)
    news[has] = told[best[has]]
    count[source] = 0
    news[source] = found[source]
    return count, news


def best_per_robot(n: int, owner: np.ndarray, key: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Per robot (of `n`), the index of its entry in `mask` with the least `key` (of equals,
    the first, in reach order: the nearest), or -1. Entries come by robot (`owner` never
    falls), so its ends bound it: the compiled pass checks no index."""
    if len(owner) and (owner[0] < 0 or owner[-1] >= n):
        raise IndexError(f"entries belong to robots {owner[0]} to {owner[-1]}, not 0 to {n - 1}")
    return _best_per_robot(n, owner, key, mask)


@njit
def _best_per_robot(
    n: int, owner: np.ndarray, key: np.ndarray, mask: np.ndarray
) -> np.ndarray:  # pragma: no cover (compiled)
    """`best_per_robot` in one pass over the entries. numpy's (a reduceat over each robot's
    run of entries, then its first entry with the least key) took four times as long, and
    `mean-shift` and `local-swap` call it four or five times a step."""
    best = np.full(n, -1, dtype=np.int64)
    for entry in range(len(owner)):
        if mask[entry]:
            robot = owner[entry]
            if best[robot] < 0 or key[entry] < key[best[robot]]:
                best[robot] = entry
    return best

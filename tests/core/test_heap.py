"""glibc's thresholds: set once a process where the user has not set them."""

from __future__ import annotations

import sys

import pytest

from swarmshape.core import heap


class Libc:
    """A C library that records what `mallopt` was asked."""

    def __init__(self) -> None:
        self.asked: list[tuple[int, int]] = []

    def mallopt(self, parameter: int, value: int) -> int:
        self.asked.append((parameter, value))
        return 1


@pytest.fixture
def libc(monkeypatch):
    found = Libc()
    monkeypatch.setattr(heap.ctypes, "CDLL", lambda _: found)
    monkeypatch.setattr(sys, "platform", "linux")
    for name in (*heap.OWN_SETTINGS, "GLIBC_TUNABLES"):
        monkeypatch.delenv(name, raising=False)
    return found


def test_the_thresholds_are_set_as_high_as_glibc_raises_them(libc):
    heap.keep_freed_memory.__wrapped__()
    assert libc.asked == [
        (heap.M_MMAP_THRESHOLD, heap.MMAP_THRESHOLD),
        (heap.M_TRIM_THRESHOLD, 2 * heap.MMAP_THRESHOLD),
    ]


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("MALLOC_MMAP_THRESHOLD_", "131072"),
        ("MALLOC_TRIM_THRESHOLD_", "131072"),
        ("GLIBC_TUNABLES", "glibc.malloc.mmap_threshold=131072"),
        ("GLIBC_TUNABLES", "glibc.malloc.check=0:glibc.malloc.trim_threshold=0"),
    ],
)
def test_a_users_own_settings_win(libc, monkeypatch, name, value):
    monkeypatch.setenv(name, value)
    heap.keep_freed_memory.__wrapped__()
    assert libc.asked == []


def test_other_systems_and_libraries_are_left_alone(libc, monkeypatch):
    monkeypatch.setattr(sys, "platform", "darwin")
    heap.keep_freed_memory.__wrapped__()
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setattr(heap.ctypes, "CDLL", lambda _: object())  # no mallopt (musl)
    heap.keep_freed_memory.__wrapped__()
    assert libc.asked == []

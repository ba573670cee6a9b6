"""A real full filesystem for the tests: a tiny tmpfs (needs root or CAP_SYS_ADMIN, Linux), and the
simulated bridge as a live source (paced in real time, like a radio)."""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess
from pathlib import Path

import pytest

from groundstation.sources import open_source


@contextlib.contextmanager
def tiny_tmpfs(folder: Path, size: str = "64k", room_bytes: int = 16_000):
    """``folder`` as a tmpfs of ``size``, filled up to ``room_bytes`` free (skips where it cannot be mounted)."""
    folder.mkdir()
    if os.name != "posix" or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root (the RLIMIT_FSIZE test covers this case without it)")
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)], capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({mounted.stderr.strip()}); the RLIMIT_FSIZE test covers this case")
    try:
        fill(folder, room_bytes)
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)


def fill(folder: Path, room_bytes: int, name: str = "filler") -> None:
    """A file that leaves ``room_bytes`` free in ``folder``'s filesystem."""
    stat = os.statvfs(folder)
    (folder / name).write_bytes(b"\0" * max(0, stat.f_bavail * stat.f_frsize - room_bytes))


def use_up(folder: Path, name: str = "filler") -> None:
    """Fill ``folder``'s filesystem to the last byte now, while a recorder may be writing into it too
    (the disk fills at a moment the test chooses, not after a number of seconds of data)."""
    with open(folder / name, "wb", buffering=0) as filler:
        block = b"\0" * os.statvfs(folder).f_frsize
        try:
            while True:
                filler.write(block)
        except OSError as error:
            if error.errno != errno.ENOSPC:
                raise


def grow(folder: Path, size: str) -> None:
    """Room comes back (the pilot freed some space): the tmpfs becomes ``size`` big."""
    subprocess.run(["mount", "-o", f"remount,size={size}", str(folder)], check=True)


def simulated_source(seed: int = 1, max_read_bytes: int | None = None):
    """The simulated bridge streaming in real time, as the app's demo does; with ``max_read_bytes``,
    read at most that many bytes at a time, as a UART driver's buffer delivers them."""
    source = open_source(f"sim:?scenario=flight&duration=600&seed={seed}")
    if max_read_bytes is not None:
        source._port = BoundedReads(source._port, max_read_bytes)
    return source


class BoundedReads:
    """A port whose reads return at most ``max_bytes``: after a stall of a loaded machine the bytes due
    come as several small chunks, not as one chunk of every second missed."""

    def __init__(self, port, max_bytes: int):
        self._port = port
        self._max_bytes = max_bytes

    def __getattr__(self, name):
        return getattr(self._port, name)

    @property
    def in_waiting(self) -> int:
        return min(self._port.in_waiting, self._max_bytes)

    def read(self, size: int = 1) -> bytes:
        return self._port.read(min(size, self._max_bytes))

"""A real full filesystem for the tests: a tiny tmpfs (needs root or CAP_SYS_ADMIN, Linux), and the
simulated bridge as a live source (paced in real time, like a radio)."""

from __future__ import annotations

import contextlib
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
        free = os.statvfs(folder).f_bavail * os.statvfs(folder).f_frsize
        (folder / "filler").write_bytes(b"\0" * max(0, free - room_bytes))
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)], check=False)


def grow(folder: Path, size: str) -> None:
    """Room comes back (the pilot freed some space): the tmpfs becomes ``size`` big."""
    subprocess.run(["mount", "-o", f"remount,size={size}", str(folder)], check=True)


def simulated_source(seed: int = 1):
    """The simulated bridge streaming in real time, as the app's demo does."""
    return open_source(f"sim:?scenario=flight&duration=600&seed={seed}")

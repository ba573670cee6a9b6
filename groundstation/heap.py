"""The C allocator's memory, where it is glibc's (Linux); elsewhere these do nothing (issue 35).

glibc keeps freed memory as the process's in two ways that our long-lived processes meet: many arrays of a
megabyte or less freed among objects that live on leave pages only a trim gives back (the batch path), and
freeing one block of 128 kB or more raises its mmap threshold to that size for good, so that every smaller
block from then on comes from the heap, whose holes it keeps (the live window)."""

from __future__ import annotations

import sys

M_MMAP_THRESHOLD = -3  # mallopt's parameter (glibc's malloc.h)
MMAP_THRESHOLD_BYTES = 128 * 1024  # glibc's own default, held


def _glibc():
    """The C library when it is glibc (it has ``malloc_trim`` and ``mallopt``), else None."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return None
    return libc if hasattr(libc, "malloc_trim") and hasattr(libc, "mallopt") else None


_LIBC = _glibc()


def give_back_freed_memory() -> None:
    """Hand the allocator's free pages back to the system (``malloc_trim``). The batch path frees many arrays of a
    megabyte or less (the decode's pieces, the frames' columns) among objects that live on: after the decode of
    4 h glibc kept 240 MB of them, which a trim of a few milliseconds gives back (bench/bench_export_memory.out.md)."""
    if _LIBC is not None:
        _LIBC.malloc_trim(0)


def keep_large_blocks_out_of_the_heap() -> None:
    """Hold glibc's mmap threshold at its default: blocks of 128 kB and more are then always mapped on their own and
    given back when freed. The live window frees such blocks all the time (the tables forget their oldest rows,
    the plot buffers grow); with the threshold raised, the app's RSS grew for 20 minutes after its data stopped
    growing (bench/bench_live_cpu.out.md). Setting it turns the raising off."""
    if _LIBC is not None:
        _LIBC.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)

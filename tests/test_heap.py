"""glibc's heap (groundstation.heap, issue 35): after a large block is freed, the next ones still stay out of it."""

import ctypes
import subprocess
import sys

import pytest

PROBE = """
import ctypes
import numpy as np
from groundstation.heap import keep_large_blocks_out_of_the_heap

class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]

libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = MallInfo2
keep_large_blocks_out_of_the_heap()
big = np.ones(1 << 20)  # 8 MB, as a live table's forgotten blocks and a plot buffer grown
del big
before = libc.mallinfo2().hblkhd
block = np.ones(1 << 17)  # 1 MB
print(libc.mallinfo2().hblkhd - before)
"""


def glibc_mallinfo2() -> bool:
    try:
        return hasattr(ctypes.CDLL("libc.so.6"), "mallinfo2")
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux") or not glibc_mallinfo2(), reason="glibc's allocator")
def test_a_large_block_freed_leaves_the_next_ones_outside_the_heap():
    """glibc maps blocks of 128 kB and more on their own and gives them back when freed, but freeing one raises
    that threshold to its size for good: the live tables forget blocks, the plot buffers grow, and from then on
    every block under their size came from the heap, whose holes are kept (the app's RSS grew with its data
    flat). In the app, a 1 MB block after an 8 MB one freed is still mapped on its own."""
    mapped = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True).stdout
    assert int(mapped) >= 1 << 20

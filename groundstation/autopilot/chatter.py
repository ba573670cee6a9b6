"""What the log libraries print while they read, caught so that it can be counted rather than shown.

pymavlink's DataFlash indexer is compiled (``dfindexer``) and writes "bad header ..." with C's
``fprintf(stderr)``, one line per damaged byte: 4,111 lines on a terminal for one corrupt 4 KB block.
Python's ``redirect_stdout`` cannot catch those, so ``caught`` points the process's file descriptors 1
and 2 at a temporary file for the call (and ``sys.stdout``/``sys.stderr``, for what the libraries
``print``). Use it around the library's calls only: anything else the process writes meanwhile would
be caught too (a progress bar keeps the stream object it was given, so only its descriptor matters).
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import os
import sys
import tempfile


class Chatter:
    """Every line a library printed inside ``caught`` blocks."""

    def __init__(self):
        self.lines: list[str] = []

    def count(self, starting: str) -> int:
        return sum(line.startswith(starting) for line in self.lines)

    def _add(self, text: str) -> None:
        self.lines += [line.strip() for line in text.splitlines() if line.strip()]

    @contextlib.contextmanager
    def caught(self, descriptors: bool = True):
        """Python's streams to a buffer for the block, and with ``descriptors`` the process's 1 and 2 to a
        temporary file (dearer: for a call into compiled code, not for each message)."""
        python = io.StringIO()
        if not descriptors:
            try:
                with contextlib.redirect_stdout(python), contextlib.redirect_stderr(python):
                    yield self
            finally:
                self._add(python.getvalue())
            return
        _flush_c_streams()
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(fd) for fd in (1, 2)]
        with tempfile.TemporaryFile() as sink:
            try:
                for fd in (1, 2):
                    os.dup2(sink.fileno(), fd)
                with contextlib.redirect_stdout(python), contextlib.redirect_stderr(python):
                    yield self
            finally:
                _flush_c_streams()
                for fd, copy in zip((1, 2), saved):
                    os.dup2(copy, fd)
                    os.close(copy)
                sink.seek(0)
                self._add(sink.read().decode("utf-8", "replace"))
                self._add(python.getvalue())


def _flush_c_streams() -> None:
    """C's buffered ``stdout`` written out, so that it lands on the descriptor it was meant for."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).fflush(None)

"""kill -9 of a process that is recording: the file opens and at most the last 0.5 s is missing."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from groundstation.recording import open_recording

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL is POSIX")

# Chunks stamped with the monotonic clock, which on POSIX is shared by all processes; one byte at
# 100 Hz, so that in the test's second the file buffer (4-8 KiB) never fills and flushes by itself.
CONTINUOUS = """
import sys, time
from groundstation.recording import RecordingWriter
writer = RecordingWriter(sys.argv[1], {"port": "kill-test"})
print("recording", flush=True)
i = 0
while True:
    writer.write_chunk(time.monotonic_ns(), bytes([i % 256]))
    i += 1
    time.sleep(0.01)
"""

# One chunk, then a quiet link: only the background flush can save it.
QUIET = """
import sys, time
from groundstation.recording import RecordingWriter
writer = RecordingWriter(sys.argv[1], {"port": "kill-test"})
writer.write_chunk(time.monotonic_ns(), b"last words")
print("recording", flush=True)
time.sleep(60)
"""


def record_then_kill(tmp_path, script: str, run_s: float) -> tuple[int, object]:
    path = tmp_path / "killed.gsrec"
    child = subprocess.Popen([sys.executable, "-c", script, str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline() == "recording\n"
        time.sleep(run_s)
        t_kill_ns = time.monotonic_ns()
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.kill()
        child.wait()
    return t_kill_ns, open_recording(path)


def test_kill_during_a_continuous_stream_loses_at_most_half_a_second(tmp_path):
    t_kill_ns, recording = record_then_kill(tmp_path, CONTINUOUS, run_s=1.0)
    assert recording.metadata["port"] == "kill-test" and not recording.closed_cleanly
    assert recording.chunk_count > 30
    chunks = list(recording.chunks())
    assert [data[0] for _, data in chunks] == [i % 256 for i in range(len(chunks))]
    assert t_kill_ns - chunks[-1][0] <= 500_000_000, (t_kill_ns - chunks[-1][0]) / 1e9
    assert all(finding.startswith("truncated tail") for finding in recording.damage), recording.damage


def test_kill_after_the_link_went_quiet_keeps_the_last_chunk(tmp_path):
    _, recording = record_then_kill(tmp_path, QUIET, run_s=0.75)
    assert [data for _, data in recording.chunks()] == [b"last words"]
    assert recording.damage == []

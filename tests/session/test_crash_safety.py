"""kill -9 of a process recording a live session: the recording opens, replays, and lost at most 0.5 s."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.replay import replay

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals and SIGKILL are POSIX only")

RECORDER = textwrap.dedent(
    """
    import sys, time
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.sources import SerialSource
    session = LiveSession(SerialSource(sys.argv[1]), Pipeline(("ahf",)), recordings_dir=sys.argv[2]).start()
    print(session.recording_path, flush=True)
    while True:
        time.sleep(1)
    """
)


def test_kill_9_mid_flight_loses_at_most_half_a_second(tmp_path):
    bridge = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "hover"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        pty = bridge.stdout.readline().split()[-1]
        recorder = subprocess.Popen([sys.executable, "-c", RECORDER, pty, str(tmp_path)], stdout=subprocess.PIPE, text=True)
        path = recorder.stdout.readline().strip()
        time.sleep(3.0)
        killed_at_ns = time.monotonic_ns()  # CLOCK_MONOTONIC is shared by every process on the machine
        recorder.send_signal(signal.SIGKILL)
        recorder.wait(timeout=10)
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)

    recording = open_recording(path)
    assert not recording.closed_cleanly
    last_chunk_ns = int(recording.chunk_t_host_ns[-1])
    assert 0 <= killed_at_ns - last_chunk_ns <= 500_000_000
    pipeline = replay(recording)
    seconds = (last_chunk_ns - int(recording.chunk_t_host_ns[0])) / 1e9
    assert len(pipeline.imu) >= 90 * (seconds - 1.0)  # 100 Hz, the boot second aside

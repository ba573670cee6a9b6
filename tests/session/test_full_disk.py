"""A live session whose disk fills up: decoding goes on, the file keeps what was written, recording
resumes into a new file when room comes back. Two real full filesystems: a tiny tmpfs (where it can
be mounted) and a per-file size limit (RLIMIT_FSIZE) in a subprocess, which needs no privilege."""

import json
import os
import subprocess
import sys
import textwrap
import time

import pytest

from groundstation.recording import open_recording
from groundstation.session.live import LiveSession
from groundstation.session.pipeline import Pipeline
from groundstation.session.replay import replay
from tests.session.full_disk import grow, simulated_source, tiny_tmpfs
from tests.waiting import wait_for


def kinds(session) -> list[str]:
    return [e["kind"] for e in session.pipeline.events]


def test_a_full_tmpfs_stops_the_recording_not_the_session_and_room_resumes_it(tmp_path):
    with tiny_tmpfs(tmp_path / "full") as folder:
        session = LiveSession(simulated_source(), Pipeline(("ahf",)), recordings_dir=folder)
        session.recorder.retry_interval_s = 0.2  # the default 5 s would only slow the test
        with session:
            first = session.recording_path
            wait_for(lambda: session.recorder.state == "failed")
            failed = next(e for e in session.pipeline.events if e["kind"] == "recording_failed")
            assert "No space left on device" in failed["message"] and failed["path"] == str(first)
            assert session.recorder.error == failed["message"]

            # Decoding goes on: the IMU table keeps growing while nothing is recorded.
            rows = len(session.pipeline.imu)
            wait_for(lambda: len(session.pipeline.imu) - rows >= 70, what="70 more IMU rows")
            assert session.running and session.error is None
            assert session.recorder.state == "failed"  # ~16 kB free is below the room needed to resume

            grow(folder, "16m")
            wait_for(lambda: session.recorder.state == "recording")
            second = session.recording_path
            assert second != first and session.recorder.paths == [first, second]
            time.sleep(0.5)
        # stop() (the with block) closed both without raising


def test_stopping_while_the_recording_has_failed_raises_nothing_and_keeps_the_file(tmp_path):
    with tiny_tmpfs(tmp_path / "full") as folder:
        session = LiveSession(simulated_source(), Pipeline(("ahf",)), recordings_dir=folder).start()
        wait_for(lambda: session.recorder.state == "failed")
        session.stop()  # closing used to raise OSError here (the buffered bytes could not be flushed)
        assert session.recorder.state == "off" and session.recorder.paths == [session.recording_path]
        recording = open_recording(session.recording_path)
        assert not recording.closed_cleanly and recording.chunk_count > 0


def test_the_files_of_a_full_disk_session_open_and_replay(tmp_path):
    with tiny_tmpfs(tmp_path / "full") as folder:
        session = LiveSession(simulated_source(), Pipeline(("ahf",)), recordings_dir=folder)
        session.recorder.retry_interval_s = 0.2
        with session:
            wait_for(lambda: session.recorder.state == "failed")
            time.sleep(0.5)
            grow(folder, "16m")
            wait_for(lambda: session.recorder.state == "recording")
            time.sleep(1.0)
        first, second = session.recorder.paths
        assert session.recorder.state == "off"

        cut = open_recording(first)  # what was written before the disk filled
        assert cut.chunk_count > 0 and len(replay(cut).imu) > 50
        assert first.stat().st_size <= 64 * 1024

        resumed = open_recording(second)
        assert resumed.closed_cleanly and resumed.damage == []
        event = next(e for _, e in resumed.events if e["kind"] == "recording_resumed")
        assert event["previous_path"] == str(first) and "No space left on device" in event["failure"]
        # The session asked the aircraft for its CONFIG again, so the new file replays at the right scales.
        assert replay(resumed).config is not None
        assert len(replay(resumed).imu) > 50
        # only the two recordings: a failed attempt to resume leaves no empty file behind
        assert sorted(p.name for p in folder.iterdir() if p.suffix == ".gsrec") == sorted([first.name, second.name])


RLIMIT_SCRIPT = textwrap.dedent(
    """
    import json, resource, signal, sys, time
    from groundstation.session.live import LiveSession
    from groundstation.session.pipeline import Pipeline
    from tests.session.full_disk import simulated_source

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead of killing
    resource.setrlimit(resource.RLIMIT_FSIZE, (12_000, 12_000))
    session = LiveSession(simulated_source(), Pipeline(("ahf",)), recordings_dir=sys.argv[1])
    session.recorder.retry_interval_s = 0.3
    session.recorder.min_free_bytes = 0  # the disk has room; each file hits the size limit
    with session:
        time.sleep(float(sys.argv[2]))
    print(json.dumps({"events": session.pipeline.events, "paths": [str(p) for p in session.recorder.paths],
                      "imu_rows": len(session.pipeline.imu), "running_error": session.error}))
    """
)


@pytest.mark.skipif(not hasattr(os, "setrlimit") and sys.platform == "win32", reason="RLIMIT_FSIZE is POSIX only")
def test_a_file_size_limit_fails_the_recording_and_the_session_decodes_on(tmp_path):
    pytest.importorskip("resource")
    seconds = 5.0
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    done = subprocess.run([sys.executable, "-c", RLIMIT_SCRIPT, str(tmp_path), str(seconds)], capture_output=True,
                          text=True, timeout=60, cwd=root)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    out = json.loads(done.stdout)
    kinds = [e["kind"] for e in out["events"]]
    assert "recording_failed" in kinds and "recording_resumed" in kinds
    failure = next(e for e in out["events"] if e["kind"] == "recording_failed")
    assert "File too large" in failure["message"]
    assert out["running_error"] is None
    assert out["imu_rows"] >= 80 * (seconds - 1.5)  # ~100 Hz throughout, the boot second aside
    assert len(out["paths"]) >= 2
    for path in out["paths"]:
        recording = open_recording(path)  # every file opens, the cut ones included
        # the last file may have been resumed just before the session stopped (a loaded machine): no chunk yet
        assert recording.chunk_count > 0 or path == out["paths"][-1]
        assert os.path.getsize(path) <= 12_000
    assert open_recording(out["paths"][0]).chunk_count > 0


def test_a_folder_that_cannot_be_recorded_into_still_gives_a_live_session(tmp_path):
    """The recording cannot even start (here /proc, which takes no files): the session decodes all the same."""
    if not sys.platform.startswith("linux"):
        pytest.skip("/proc is Linux's")
    session = LiveSession(simulated_source(), Pipeline(("ahf",)), recordings_dir="/proc/groundstation").start()
    try:
        assert session.recorder.state == "failed" and session.recording_path is None
        assert "cannot record into /proc/groundstation" in session.recorder.error
        assert kinds(session)[0] == "recording_failed"
        wait_for(lambda: len(session.pipeline.imu) > 50)
    finally:
        session.stop()

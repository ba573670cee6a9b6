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
from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import replay
from tests.session.full_disk import grow, simulated_source, tiny_tmpfs
from tests.waiting import LIMIT_S, wait_for


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
            grow(folder, "16m")
            wait_for(lambda: session.recorder.state == "recording")
            rows = len(session.pipeline.imu)
            # the new file's own CONFIG (asked for on resuming) and rows to replay, however slowly they come
            wait_for(lambda: "config" in kinds(session)[kinds(session).index("recording_resumed"):]
                     and len(session.pipeline.imu) >= rows + 100, what="the CONFIG and 100 rows after resuming")
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


FILE_LIMIT_BYTES = 12_000
RLIMIT_SCRIPT = textwrap.dedent(
    f"""
    import json, resource, signal, sys
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from tests.session.full_disk import simulated_source
    from tests.waiting import LIMIT_S, wait_for

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead of killing
    resource.setrlimit(resource.RLIMIT_FSIZE, ({FILE_LIMIT_BYTES}, {FILE_LIMIT_BYTES}))
    # chunks of at most 2 kB, as from a UART: each file has room for some (one chunk of every second a loaded
    # machine kept the reader away could be bigger than a whole file, which then holds none)
    session = LiveSession(simulated_source(max_read_bytes=2048), Pipeline(("ahf",)), recordings_dir=sys.argv[1])
    session.recorder.retry_interval_s = 0.3
    session.recorder.min_free_bytes = 0  # the disk has room; each file hits the size limit
    with session:
        wait_for(lambda: session.recorder.state == "failed", what="the first file's failure")
        rows_at_failure = len(session.pipeline.imu)
        wait_for(lambda: len(session.recorder.paths) >= 3 and len(session.pipeline.imu) >= rows_at_failure + 200,
                 what="two resumptions and 200 rows")
    print(json.dumps({{"events": session.pipeline.events, "paths": [str(p) for p in session.recorder.paths],
                      "rows_after_failure": len(session.pipeline.imu) - rows_at_failure, "running_error": session.error}}))
    """
)


@pytest.mark.skipif(not hasattr(os, "setrlimit") and sys.platform == "win32", reason="RLIMIT_FSIZE is POSIX only")
def test_a_file_size_limit_fails_the_recording_and_the_session_decodes_on(tmp_path):
    pytest.importorskip("resource")
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    # the script's two waits have LIMIT_S each; the rest is its start and stop
    done = subprocess.run([sys.executable, "-c", RLIMIT_SCRIPT, str(tmp_path)], capture_output=True, text=True,
                          timeout=3 * LIMIT_S, cwd=root)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr
    out = json.loads(done.stdout)
    assert out["running_error"] is None and out["rows_after_failure"] >= 200  # decoding went on past the failures
    failed = [e for e in out["events"] if e["kind"] == "recording_failed"]
    resumed = [e for e in out["events"] if e["kind"] == "recording_resumed"]
    assert all("File too large" in e["message"] for e in failed)
    paths = out["paths"]
    # each failure names the file that failed, each resumption the file it failed in and the new one
    assert [e["path"] for e in failed] == paths[:len(failed)] and len(failed) >= len(paths) - 1
    assert [(e["previous_path"], e["path"]) for e in resumed] == list(zip(paths, paths[1:]))
    for path in paths:
        recording = open_recording(path)  # every file opens, the cut ones included
        # the last file may have been resumed just before the session stopped: no chunk yet
        assert recording.chunk_count > 0 or path == paths[-1]
        assert os.path.getsize(path) <= FILE_LIMIT_BYTES


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

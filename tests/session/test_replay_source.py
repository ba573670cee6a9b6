"""Replay pacing, and replaying damaged recordings."""

import time
from pathlib import Path

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.replay import replay
from groundstation.sources import ReplaySource, SourceClosed
from tests.cli_in_process import run_in_process

SAMPLE = Path(__file__).resolve().parents[2] / "recordings" / "samples" / "hover-raw.gsrec"


def drain(source, limit_s: float = 30.0) -> list:
    chunks, deadline = [], time.monotonic() + limit_s
    while time.monotonic() < deadline:
        try:
            chunk = source.read()
        except SourceClosed:
            return chunks
        if chunk is not None:
            chunks.append(chunk)
    raise AssertionError("replay did not end")


def test_as_fast_as_possible_gives_every_chunk_with_its_recorded_time():
    recording = open_recording(SAMPLE)
    chunks = drain(ReplaySource(recording))
    assert [c.t_host_ns for c in chunks] == recording.chunk_t_host_ns.tolist()
    assert b"".join(c.data for c in chunks) == b"".join(d for _, d in recording.chunks())


def test_paced_replay_is_not_faster_than_asked():
    source = ReplaySource(open_recording(SAMPLE), speed=64.0)
    start = time.monotonic()
    drain(source)
    assert time.monotonic() - start >= source.duration_s / 64.0 * 0.95


def test_speed_outside_the_range_is_refused():
    with pytest.raises(ValueError, match="between"):
        ReplaySource(open_recording(SAMPLE), speed=100.0)


def test_a_recording_cut_off_mid_record_replays_what_it_holds(tmp_path, capsys):
    cut = tmp_path / "cut.gsrec"
    data = SAMPLE.read_bytes()
    cut.write_bytes(data[: len(data) // 6 + 7])  # mid-record, inside the link bytes (the truth block comes last)
    whole = replay(open_recording(SAMPLE)).imu.array()
    recording = open_recording(cut)
    assert any("truncated" in finding for finding in recording.damage)
    part = replay(recording).imu.array()
    assert 0.1 * len(whole) < len(part) < len(whole)
    np.testing.assert_array_equal(part, whole[: len(part)])  # what survives is exactly the flight's start

    result = run_in_process(capsys, "export", cut, "--out", tmp_path / "cut.csv")
    assert result.returncode == 0 and "warning: truncated" in result.stdout

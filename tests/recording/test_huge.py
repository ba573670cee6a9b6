"""Crafted and huge files (issue 22): the reader's time and memory stay bounded whatever the file holds.

Bounds are counted, never timed: bytes hashed by CRC-32, tracemalloc's peak, a subprocess's maxrss."""

import json
import subprocess
import sys
import tracemalloc
import zlib

import pytest

from firmware_protocol import DecoderStats
from groundstation.recording import open_recording
from groundstation.recording.format import RecordingError
from groundstation.session_parts.link import LinkStats
from tests.crafted_files import chunk_time_jump, false_markers, link_recording, sparse_zeros


@pytest.fixture
def crc_bytes(monkeypatch):
    """Counts the bytes every zlib.crc32 call hashes (the reader's work on a damaged file)."""
    counted = [0]
    crc32 = zlib.crc32

    def counting(data, value=0):
        counted[0] += memoryview(data).nbytes
        return crc32(data, value)

    monkeypatch.setattr(zlib, "crc32", counting)
    return counted


def test_false_record_markers_cost_crc_work_linear_in_the_file(tmp_path, crc_bytes):
    path = false_markers(tmp_path, "false", false_bytes=256 * 1024, claimed_bytes=64 * 1024)
    intact = open_recording(tmp_path / "false-intact.gsrec")
    crc_bytes[0] = 0
    recording = open_recording(path)
    size = path.stat().st_size
    # Checked one by one, each of the 15,420 false headers would hash its 64 KiB: 1 GB for 0.4 MB.
    # Searched in windows, each byte is hashed about once, plus one claimed length per window.
    assert crc_bytes[0] <= 3 * size, (crc_bytes[0], size)
    assert list(recording.chunks()) == list(intact.chunks()) and recording.closed_cleanly
    (finding,) = recording.damage
    assert finding.startswith("unreadable bytes") and f"({15420 * 17} bytes)" in finding


PEAK_RSS = """
import json, resource, sys
from groundstation.recording import open_recording
from groundstation.recording.format import RecordingError
try:
    open_recording(sys.argv[1])
    message = None
except RecordingError as error:
    message = str(error)
print(json.dumps({"message": message, "maxrss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""


def peak_rss(path) -> tuple[str | None, float]:
    """(the RecordingError's message or None, the peak resident memory in MiB) of opening ``path`` in a fresh process."""
    out = subprocess.run([sys.executable, "-c", PEAK_RSS, str(path)], capture_output=True, text=True, check=True).stdout
    result = json.loads(out)
    return result["message"], result["maxrss_kib"] / 1024


def test_a_huge_file_of_zeros_is_refused_from_its_first_bytes(tmp_path):
    path = sparse_zeros(tmp_path, "zeros", size_bytes=2 * 2**30)
    baseline_message, baseline_mib = peak_rss(sparse_zeros(tmp_path, "small", size_bytes=1024))
    message, mib = peak_rss(path)
    assert "is not a groundstation recording" in message and "binary data" in message
    # Only the first longest record's worth (16 MiB) may be looked at, not 2 GiB.
    assert mib - baseline_mib < 64, (mib, baseline_mib)


def test_opening_a_recording_allocates_a_fraction_of_its_size(tmp_path):
    path = link_recording(tmp_path / "plain.gsrec", megabytes=8)
    size = path.stat().st_size
    tracemalloc.start()
    try:
        recording = open_recording(path)
        opened = tracemalloc.get_traced_memory()[1]
        tracemalloc.reset_peak()
        data, ends, _ = recording.stream()
        streamed = tracemalloc.get_traced_memory()[1] - opened
    finally:
        tracemalloc.stop()
    # The file is mapped, not read: what is allocated is the chunk index, 24 bytes a chunk.
    assert opened < 0.5 * size, (opened, size)
    # The joined chunk bytes once (they are most of the file), not a mask and a copy besides.
    assert streamed < 1.2 * len(data) + 64 * 1024, (streamed, len(data))
    assert len(data) == ends[-1] and recording.damage == []


def test_a_jump_of_2_62_ns_in_chunk_time_is_damage_and_costs_nothing(tmp_path):
    from groundstation.session_makers.load import load_session

    path = chunk_time_jump(tmp_path, "jump", jump_ns=2**62)
    tracemalloc.start()
    try:
        session = load_session(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20, peak
    assert any("jumps forward by more than a year 1 time(s)" in finding for finding in session.damage)
    # Two seconds of data each side of the jump, the silence in between two rows of zeros.
    assert len(session.link.per_second["t_s"]) <= 2 + 2 + 2


def test_a_silence_adds_two_rows_of_zeros_not_one_per_second():
    link = LinkStats()
    counters = DecoderStats()
    link.on_chunk(0, counters, 1)
    counters.frames = 100
    link.on_chunk(10**6 * 10**9 + 1, counters, 1)  # eleven days later
    counters.frames = 150
    link.on_chunk(10**6 * 10**9 + 10**9, counters, 1)
    rows = link.per_second.array()
    assert rows[:, 0].tolist() == [0, 1, 999_999, 1_000_000]
    assert rows[:, 1].tolist() == [100, 0, 0, 50]  # every frame counted once, as before


def test_a_folder_or_a_device_is_one_line(tmp_path):
    with pytest.raises(RecordingError, match="is a folder"):
        open_recording(tmp_path)
    with pytest.raises(RecordingError, match="not a regular file"):
        open_recording("/dev/zero")  # read whole, it would never end

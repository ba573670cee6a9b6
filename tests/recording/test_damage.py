"""Damaged files: every intact record is recovered and every loss is reported with its size."""

from __future__ import annotations

import io
import re
import zipfile

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from groundstation.errors import UserError
from groundstation.recording import RecordingError, open_recording
from groundstation.recording.format import Kind, encode_preamble, encode_record

from .helpers import PREAMBLE_BYTES, write_small


@pytest.fixture
def small(tmp_path):
    return write_small(tmp_path / "small.gsrec")


def reopen(tmp_path, data: bytes, name: str = "damaged.gsrec"):
    path = tmp_path / name
    path.write_bytes(data)
    return open_recording(path)


def intact_chunks(small, lost: set[int]):
    return [c for i, c in enumerate(small.chunks) if i not in lost]


def test_truncation_at_every_offset_keeps_every_record_before_the_cut(tmp_path, small):
    metadata_end = small.spans[0][1]
    for cut in range(len(small.data)):
        data = small.data[:cut]
        if cut < metadata_end:
            with pytest.raises(RecordingError):
                reopen(tmp_path, data)
            continue
        recording = reopen(tmp_path, data)
        complete = [i for i in range(len(small.chunks)) if small.chunk_span(i)[1] <= cut]
        assert list(recording.chunks()) == [small.chunks[i] for i in complete], cut
        assert not recording.closed_cleanly
        if cut in {end for _, end in small.spans}:
            assert recording.damage == [], cut
        else:
            cut_record_start = max(start for start, _ in small.spans if start <= cut)
            assert recording.damage == [
                f"truncated tail: last {cut - cut_record_start} bytes of an incomplete record ignored"
                " (the recording was cut off)"
            ], cut


def test_cut_inside_the_first_record_says_so(tmp_path, small):
    assert open_recording_error(tmp_path, small.data[:0]) == "is empty (0 bytes): nothing was recorded"
    assert "ends inside its header (5 bytes)" in open_recording_error(tmp_path, small.data[:5])
    assert "ends inside its header (12 bytes)" in open_recording_error(tmp_path, small.data[:12])
    assert "nothing could be read: truncated tail" in open_recording_error(tmp_path, small.data[:40])


def open_recording_error(tmp_path, data: bytes) -> str:
    with pytest.raises(RecordingError) as caught:
        reopen(tmp_path, data)
    assert isinstance(caught.value, UserError)  # so the command line shows it and exits 2
    return str(caught.value).split(".gsrec", 1)[1].lstrip(": ").strip()


@settings(max_examples=80, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(where=st.integers(min_value=0), garbage=st.binary(min_size=1, max_size=500))
@example(where=1, garbage=b"\xf3")  # repeats the record marker's first byte: the record stays whole
def test_garbage_inserted_anywhere_after_the_metadata_loses_only_the_record_it_lands_in(tmp_path, small, where, garbage):
    metadata_end = small.spans[0][1]
    at = metadata_end + where % (len(small.data) - metadata_end)
    damaged = small.data[:at] + garbage + small.data[at:]
    recording = reopen(tmp_path, damaged)
    broken = [(s, e) for s, e in small.spans if s < at < e and not still_whole(small.data[s:e], damaged, s, len(garbage))]
    lost = {i for i in range(len(small.chunks)) if small.chunk_span(i) in broken}
    assert list(recording.chunks()) == intact_chunks(small, lost)
    assert len(recording.damage) == 1
    lost_bytes = len(garbage) + sum(e - s for s, e in broken)
    # Garbage in the last record's length field can make it look cut off: reported as a truncated tail.
    assert re.fullmatch(rf".*skipped \({lost_bytes} bytes\)|truncated tail: last {lost_bytes} bytes .*", recording.damage[0])


def still_whole(record: bytes, damaged: bytes, start: int, garbage_bytes: int) -> bool:
    """True when the inserted garbage happens to leave the record's bytes whole (e.g. garbage that
    repeats the record's first bytes), so the record is rightly recovered and only the garbage lost."""
    return record in (damaged[start : start + len(record)], damaged[start + garbage_bytes : start + garbage_bytes + len(record)])


def test_garbage_between_records_is_reported_with_its_place_and_size(tmp_path, small):
    at = small.chunk_span(3)[0]
    recording = reopen(tmp_path, small.data[:at] + b"\x00" * 250 + small.data[at:])
    assert list(recording.chunks()) == small.chunks
    assert recording.damage == [f"unreadable bytes {at}–{at + 250} skipped (250 bytes)"]
    assert recording.events == [(9_000_000, {"note": "end"})] and recording.closed_cleanly


def test_a_flipped_bit_in_one_record_loses_that_record_only(tmp_path, small):
    for index, (start, end) in enumerate(small.spans):
        for bit in range(8 * start, 8 * end, 3):  # every third bit of every record
            data = bytearray(small.data)
            data[bit // 8] ^= 1 << (bit % 8)
            recording = reopen(tmp_path, bytes(data))
            chunk_index = index - 1 if 1 <= index <= len(small.chunks) else None
            assert list(recording.chunks()) == intact_chunks(small, {chunk_index}), bit
            assert re.fullmatch(
                rf"(record at byte {start} failed its CRC;|unreadable bytes {start}–{end}) skipped \({end - start} bytes\)"
                # A flipped length bit in the last record can make it look cut off.
                rf"|truncated tail: last {end - start} bytes .*",
                recording.damage[0],
            ), (bit, recording.damage)
            if index == 0:
                assert recording.metadata == {} and "metadata record lost" in recording.damage[1]
            else:
                assert recording.metadata["port"] == "t" and len(recording.damage) == 1
            assert recording.closed_cleanly == (index != len(small.spans) - 1)
            assert len(recording.events) == (0 if index == len(small.spans) - 2 else 1)


def test_a_crc_failure_names_the_record(tmp_path, small):
    start, end = small.chunk_span(2)
    data = bytearray(small.data)
    data[end - 6] ^= 0x10  # in the payload: marker and length still agree with the next record
    recording = reopen(tmp_path, bytes(data))
    assert recording.damage == [f"record at byte {start} failed its CRC; skipped ({end - start} bytes)"]


def test_a_flipped_bit_in_the_file_identification_still_yields_everything(tmp_path, small):
    for bit in range(8 * PREAMBLE_BYTES):
        data = bytearray(small.data)
        data[bit // 8] ^= 1 << (bit % 8)
        recording = reopen(tmp_path, bytes(data))
        assert list(recording.chunks()) == small.chunks and recording.metadata["port"] == "t"
        assert len(recording.damage) == 1 and "damaged" in recording.damage[0], bit
        assert recording.version == 1


def test_records_after_foreign_bytes_at_the_start_are_recovered(tmp_path, small):
    recording = reopen(tmp_path, b"junk" * 10 + small.data[PREAMBLE_BYTES:])
    assert list(recording.chunks()) == small.chunks
    assert recording.damage == ["file identification damaged (bytes 0–40 before the first intact record); read as format version 1"]


def test_unreadable_bytes_at_the_end(tmp_path, small):
    recording = reopen(tmp_path, small.data + b"\x00" * 30)
    assert list(recording.chunks()) == small.chunks
    assert recording.damage == [f"unreadable bytes {len(small.data)}–{len(small.data) + 30} skipped (30 bytes)"]


def png() -> bytes:
    return b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(100)


def xlsx() -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        archive.writestr("xl/workbook.xml", "<workbook/>")
    return buffer.getvalue()


@pytest.mark.parametrize("data, expected", [
    (png(), "is not a groundstation recording: it looks like a PNG image"),
    (xlsx(), "is not a groundstation recording: it looks like a ZIP archive"),
    (b"\x1f\x8b\x08\x00" + bytes(60), "it looks like a gzip file"),
    (b"time_s,gyr_x_rad_s,gyr_y_rad_s\n0.0,0.1,0.2\n", "it looks like text, CSV-like (for a dataset CSV use 'groundstation import"),
    (b"hello world\n" * 3, "it looks like text"),
    (bytes(range(256)), "it looks like binary data of an unknown format"),
    (b"\x89GS", "ends inside its header (3 bytes): nothing was recorded"),
])
def test_other_formats_are_refused_with_a_clear_message(tmp_path, data, expected):
    assert expected in open_recording_error(tmp_path, data)


def test_a_missing_file(tmp_path):
    with pytest.raises(RecordingError, match="no such file"):
        open_recording(tmp_path / "nope.gsrec")


def test_only_garbage_after_the_header(tmp_path):
    message = open_recording_error(tmp_path, encode_preamble() + b"\x00" * 100)
    assert message == "nothing could be read: unreadable bytes 12–112 skipped (100 bytes)"


def test_a_newer_format_version_is_refused_clearly(tmp_path):
    newer = encode_preamble(2) + encode_record(Kind.METADATA, 0, b'{"format_version": 2}') + encode_record(Kind.CHUNK, 1, b"x")
    message = open_recording_error(tmp_path, newer)
    assert message.startswith("was written by a newer groundstation (recording format version 2;")
    assert "update groundstation" in message


def test_a_record_kind_from_the_future_is_skipped_and_reported(tmp_path, small):
    end_start = small.spans[-1][0]
    data = small.data[:end_start] + encode_record(9, 5, b"later") + small.data[end_start:]
    recording = reopen(tmp_path, data)
    assert list(recording.chunks()) == small.chunks
    assert recording.damage == [f"record of unknown kind 9 at byte {end_start} skipped (written by a newer groundstation?)"]


def test_an_intact_record_with_a_bad_payload_is_reported(tmp_path, small):
    end_start = small.spans[-1][0]
    extra = encode_record(Kind.EVENT, 5, b"[1, 2]") + encode_record(Kind.SAMPLES, 6, b"\x02\x00\x00\x00{}")
    recording = reopen(tmp_path, small.data[:end_start] + extra + small.data[end_start:])
    assert recording.events == [(9_000_000, {"note": "end"})]
    assert recording.damage[0] == f"event record at byte {end_start} is not a JSON object; skipped"
    assert recording.damage[1].startswith("samples record at byte ") and recording.damage[1].endswith("; skipped")

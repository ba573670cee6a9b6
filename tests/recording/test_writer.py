"""The writer refuses what would lose or corrupt a recording, and says why."""

from __future__ import annotations

import math

import numpy as np
import pytest

from groundstation.recording import RecordingError, RecordingWriter, open_recording


def test_an_existing_file_is_never_overwritten(tmp_path):
    path = tmp_path / "old.gsrec"
    path.write_bytes(b"a precious flight")
    with pytest.raises(RecordingError, match="already exists; a recording is never overwritten"):
        RecordingWriter(path, {})
    assert path.read_bytes() == b"a precious flight"


def test_a_folder_that_does_not_exist(tmp_path):
    with pytest.raises(RecordingError, match="cannot create the recording .*No such file or directory"):
        RecordingWriter(tmp_path / "missing" / "r.gsrec", {})


def test_bad_metadata_is_refused_before_the_file_is_created(tmp_path):
    with pytest.raises(TypeError, match="metadata must be a dict"):
        RecordingWriter(tmp_path / "a.gsrec", [("port", "x")])
    with pytest.raises(ValueError):
        RecordingWriter(tmp_path / "a.gsrec", {"beta": math.nan})
    assert not (tmp_path / "a.gsrec").exists()


def test_bad_events_and_samples_are_refused_and_the_recording_goes_on(tmp_path):
    path = tmp_path / "r.gsrec"
    with RecordingWriter(path, {}) as writer:
        with pytest.raises(TypeError, match="event must be a dict"):
            writer.write_event(1, "connected")
        with pytest.raises(ValueError, match="differ in length"):
            writer.write_samples({"a": np.zeros(3), "b": np.zeros(4)})
        with pytest.raises(ValueError, match="cannot hold exactly"):
            writer.write_samples({"a": np.array([2**53 + 1], dtype=np.int64)})
        with pytest.raises(ValueError, match="1-D numeric"):
            writer.write_samples({"a": np.array(["x"])})
        writer.write_chunk(2, b"still recording")
    recording = open_recording(path)
    assert list(recording.chunks()) == [(2, b"still recording")] and recording.damage == []


def test_writing_after_close_is_an_error_and_close_twice_is_not(tmp_path):
    writer = RecordingWriter(tmp_path / "c.gsrec", {})
    writer.close()
    writer.close()
    with pytest.raises(ValueError, match="is closed"):
        writer.write_chunk(1, b"x")


def test_the_file_is_closed_cleanly_even_when_the_block_raises(tmp_path):
    path = tmp_path / "e.gsrec"
    with pytest.raises(KeyError):
        with RecordingWriter(path, {}) as writer:
            writer.write_chunk(1, b"kept")
            raise KeyError("boom")
    recording = open_recording(path)
    assert recording.closed_cleanly and list(recording.chunks()) == [(1, b"kept")]

"""What is written is read back exactly: chunks, events, samples, metadata."""

from __future__ import annotations

import gzip
import json
import threading
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from firmware_protocol import SPEC
from groundstation import __version__
from groundstation.recording import FORMAT_VERSION, RecordingWriter, open_recording
from groundstation.recording.format import MARKER

BROAD = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "broad"
INT64 = st.integers(min_value=-(2**63), max_value=2**63 - 1)
# Raw link bytes, with the record marker now and then: a reader that trusted markers would break.
LINK_BYTES = st.lists(st.one_of(st.binary(max_size=300), st.just(MARKER), st.just(MARKER * 3)), max_size=4).map(b"".join)
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**53), 2**53) | st.floats(allow_nan=False, allow_infinity=False) | st.text(),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3),
    max_leaves=8,
)


def new_path(tmp_path: Path) -> Path:
    return tmp_path / f"r{len(list(tmp_path.iterdir()))}.gsrec"


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
# A record that repeats an earlier one (kind, time and bytes) is a duplicated byte range, read once
# (test_damaged_imports.py): the writer never writes one twice, so neither do these lists.
@given(chunks=st.lists(st.tuples(INT64, LINK_BYTES), max_size=40, unique=True),
       events=st.lists(st.tuples(INT64, st.dictionaries(st.text(max_size=8), JSON_VALUES, max_size=4)), max_size=5,
                       unique_by=lambda e: (e[0], json.dumps(e[1], sort_keys=True))))
def test_chunks_and_events_round_trip(tmp_path, chunks, events):
    path = new_path(tmp_path)
    with RecordingWriter(path, {"port": "loop://", "baud": 115200}) as writer:
        for t_host_ns, data in chunks:
            writer.write_chunk(t_host_ns, data)
        for t_host_ns, event in events:
            writer.write_event(t_host_ns, event)
    recording = open_recording(path)
    assert list(recording.chunks()) == chunks
    assert recording.events == events
    # Any int64 time round-trips; a step forward by more than a year (Python ints: no wrap) is said.
    year_ns = 365 * 24 * 3600 * 10**9
    jumps = sum(b - a > year_ns for (a, _), (b, _) in zip(chunks, chunks[1:]))
    assert len(recording.damage) == (jumps > 0) and recording.closed_cleanly
    assert all(f"more than a year {jumps} time(s)" in finding for finding in recording.damage)
    assert recording.record_counts == {"chunks": len(chunks), "events": len(events), "sample_blocks": 0}
    assert recording.chunk_t_host_ns.tolist() == [t for t, _ in chunks]


def test_metadata_keeps_the_callers_fields_and_adds_the_format_fields(tmp_path):
    caller = {"port": "/dev/ttyACM0", "baud": 921600, "mounting": 3, "estimators": {"ahf": {"beta": 0.033}}}
    with RecordingWriter(tmp_path / "m.gsrec", caller):
        pass
    recording = open_recording(tmp_path / "m.gsrec")
    metadata = recording.metadata
    assert {k: metadata[k] for k in caller} == caller
    assert metadata["format_version"] == recording.version == FORMAT_VERSION
    assert metadata["app_version"] == __version__
    assert metadata["protocol_version"] == SPEC.protocol_version
    assert metadata["protocol_fingerprint"] == SPEC.fingerprint
    assert metadata["start_utc"].endswith("Z") and len(metadata["start_utc"]) == len("2026-11-21T18:32:53.123Z")
    assert recording.t_open_ns is not None and recording.chunk_count == 0 and recording.samples == {}


def test_a_callers_start_time_is_kept(tmp_path):
    with RecordingWriter(tmp_path / "s.gsrec", {"start_utc": "2026-11-21T18:32:53Z"}):
        pass
    assert open_recording(tmp_path / "s.gsrec").metadata["start_utc"] == "2026-11-21T18:32:53Z"


def test_chunk_access_by_index_and_from_an_index(tmp_path):
    chunks = [(i * 10, bytes([i]) * i) for i in range(20)]
    with RecordingWriter(tmp_path / "i.gsrec", {}) as writer:
        for chunk in chunks:
            writer.write_chunk(*chunk)
    recording = open_recording(tmp_path / "i.gsrec")
    assert recording.chunk(7) == chunks[7]
    assert list(recording.chunks(15)) == chunks[15:]


@settings(max_examples=30, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(values=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=0, max_size=50))
def test_samples_are_kept_bit_for_bit(tmp_path, values):
    path = new_path(tmp_path)
    a = np.array(values, dtype=np.float64)
    columns = {"time_s": a, "neg": -a, "moving": (np.arange(len(a)) % 2).astype(np.int8)}
    with RecordingWriter(path, {}) as writer:
        writer.write_samples(columns)
    samples = open_recording(path).samples
    assert list(samples) == list(columns)
    for name, column in columns.items():
        assert samples[name].dtype == np.float64
        # Bit patterns, so that NaN payloads and -0.0 count too.
        assert samples[name].view(np.int64).tolist() == column.astype(np.float64).view(np.int64).tolist()


def test_samples_written_in_several_calls_are_joined_in_order(tmp_path):
    with RecordingWriter(tmp_path / "j.gsrec", {}) as writer:
        writer.write_samples({"a": np.arange(3.0), "b": np.zeros(3)})
        writer.write_samples({"a": np.arange(3.0, 5.0), "b": np.ones(2)})
    samples = open_recording(tmp_path / "j.gsrec").samples
    assert samples["a"].tolist() == [0, 1, 2, 3, 4] and samples["b"].tolist() == [0, 0, 0, 1, 1]


@pytest.mark.skipif(not BROAD.is_dir(), reason="the shared BROAD dataset is not here")
def test_a_whole_dataset_trial_imports_exactly(tmp_path):
    """Several SAMPLES blocks (the trial is bigger than one), NaN truth cells, 0/1 'moving'."""
    with gzip.open(BROAD / "02_undisturbed_slow_rotation_B.csv.gz", "rt") as f:
        frame = pd.read_csv(f)
    columns = {name: frame[name].to_numpy() for name in frame.columns}
    with RecordingWriter(tmp_path / "broad.gsrec", {"source": "import"}) as writer:
        writer.write_samples(columns)
    recording = open_recording(tmp_path / "broad.gsrec")
    assert recording.record_counts["sample_blocks"] > 1 and recording.damage == []
    for name, column in columns.items():
        assert np.array_equal(recording.samples[name], column.astype(np.float64), equal_nan=True), name
        assert recording.samples[name].view(np.int64).tolist() == column.astype(np.float64).view(np.int64).tolist()


def test_a_read_bigger_than_a_record_is_split_and_joins_back(tmp_path, monkeypatch):
    monkeypatch.setattr("groundstation.recording.writer.CHUNK_SPLIT_BYTES", 1000)
    data = bytes(range(256)) * 10
    with RecordingWriter(tmp_path / "big.gsrec", {}) as writer:
        writer.write_chunk(5, data)
    recording = open_recording(tmp_path / "big.gsrec")
    assert [t for t, _ in recording.chunks()] == [5, 5, 5]
    assert b"".join(d for _, d in recording.chunks()) == data


def test_one_thread_writes_chunks_while_another_writes_events(tmp_path):
    path = tmp_path / "threads.gsrec"
    chunks = [(i, i.to_bytes(4, "little") * 5) for i in range(5000)]
    events = [(i, {"i": i, "text": "x" * (i % 50)}) for i in range(500)]
    with RecordingWriter(path, {}) as writer:
        threads = [
            threading.Thread(target=lambda: [writer.write_chunk(*c) for c in chunks]),
            threading.Thread(target=lambda: [writer.write_event(*e) for e in events]),
        ]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    recording = open_recording(path)
    assert recording.damage == []
    assert list(recording.chunks()) == chunks and recording.events == events


def test_fsync_setting_writes_the_same_file(tmp_path):
    with RecordingWriter(tmp_path / "f.gsrec", {}, fsync=True) as writer:
        writer.write_chunk(1, b"abc")
    assert list(open_recording(tmp_path / "f.gsrec").chunks()) == [(1, b"abc")]

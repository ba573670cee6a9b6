"""Crafted recordings: valid checksums, hostile content (issue 22, "Crafted and huge files"). Each
``CRAFTED`` entry writes one file into a folder; tests run every command on each and want a one-line
message or a clean result, never a traceback. ``python -m tests.crafted_files DIR`` writes them all."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from groundstation.recording import RecordingWriter
from groundstation.sim.stream import Scenario, SimStream

DEEP = 100_000  # JSON nested this deep: Python's json recursion limit is far below


def _link_bytes(writer: RecordingWriter, seconds: float = 2.0) -> None:
    stream = SimStream(Scenario(profile="hover", duration_s=seconds, seed=3))
    for chunk in [*stream.advance(stream.end_s), *stream.flush()]:
        writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)


def _recording(folder: Path, name: str, metadata: dict, events=(), samples=None, link=True) -> Path:
    path = folder / f"{name}.gsrec"
    with RecordingWriter(path, metadata) as writer:
        if link:
            _link_bytes(writer)
        for t_ns, event in events:
            writer.write_event(t_ns, event)
        if samples is not None:
            writer.write_samples(samples)
    return path


def _deep_json_event(folder: Path, name: str) -> Path:
    """An event record whose JSON is nested DEEP levels (its checksum valid)."""
    from groundstation.recording import format as fmt

    path = _recording(folder, name, {"source": "crafted"})
    payload = ("[" * DEEP + "]" * DEEP).encode()
    with path.open("ab") as handle:
        handle.write(fmt.encode_record(fmt.Kind.EVENT, 10**9, payload))
    return path


CRAFTED = {
    "settings_not_a_dict": lambda d, n: _recording(d, n, {"estimator_settings": [1, 2, 3]}),
    "settings_values_text": lambda d, n: _recording(d, n, {"estimator_settings": {"hf": {"beta": "fast"}}}),
    "settings_of_unknown_estimator": lambda d, n: _recording(d, n, {"estimator_settings": {"zz9": {"beta": 1.0}}}),
    "filters_not_a_list": lambda d, n: _recording(d, n, {"filters": 42}),
    "filters_unknown_names": lambda d, n: _recording(d, n, {"filters": ["ahf", "no_such_filter"]}),
    "settings_event_of_a_newer_version": lambda d, n: _recording(
        d, n, {"filters": ["hf"]}, events=[(10**9, {"kind": "settings", "name": "hf", "settings": {"warp_drive": 2.0}})]),
    "settings_event_without_settings": lambda d, n: _recording(d, n, {}, events=[(10**9, {"kind": "settings", "name": "hf"})]),
    "event_not_an_object": lambda d, n: _recording(d, n, {}, events=[(10**9, {"kind": 7})]),
    "deep_json_event": _deep_json_event,
    "samples_without_time": lambda d, n: _recording(d, n, {"source": "import"}, link=False,
                                                    samples={"gyr_x_rad_s": np.zeros(10), "acc_x_m_s2": np.ones(10)}),
    "samples_zero_rows": lambda d, n: _recording(d, n, {"source": "import"}, link=False,
                                                 samples={"time_s": np.zeros(0), "gyr_x_rad_s": np.zeros(0)}),
}


def write_all(folder: Path) -> dict[str, Path]:
    folder.mkdir(parents=True, exist_ok=True)
    return {name: make(folder, name) for name, make in CRAFTED.items()}


def false_markers(folder: Path, name: str, false_bytes: int = 2 * 2**20, claimed_bytes: int = 64 * 1024) -> Path:
    """A recording with ``false_bytes`` of false record headers before its END record, each claiming a
    ``claimed_bytes`` payload that is there (so checking each costs a CRC over it), none intact."""
    from groundstation.recording import format as fmt

    intact = _recording(folder, f"{name}-intact", {"source": "crafted"}).read_bytes()
    end_record = len(fmt.encode_record(fmt.Kind.END, 0, b""))
    header = fmt.RECORD_HEADER.pack(fmt.MARKER, fmt.Kind.CHUNK, claimed_bytes, 0)
    path = folder / f"{name}.gsrec"
    path.write_bytes(intact[:-end_record] + header * (false_bytes // len(header)) + intact[-end_record:])
    return path


def sparse_zeros(folder: Path, name: str, size_bytes: int = 2 * 2**30) -> Path:
    """A file of ``size_bytes`` zeros that takes no disk (sparse): reading it whole would take that memory."""
    path = folder / f"{name}.gsrec"
    with path.open("wb") as handle:
        handle.truncate(size_bytes)
    return path


def chunk_time_jump(folder: Path, name: str, jump_ns: int = 2**62) -> Path:
    """A recording whose second half of chunks arrived ``jump_ns`` after the first (valid checksums)."""
    stream = SimStream(Scenario(profile="hover", duration_s=2.0, seed=3))
    chunks = [*stream.advance(stream.end_s), *stream.flush()]
    path = folder / f"{name}.gsrec"
    with RecordingWriter(path, {"source": "crafted"}) as writer:
        for i, chunk in enumerate(chunks):
            writer.write_chunk(int(chunk.t_s * 1e9) + (jump_ns if i >= len(chunks) // 2 else 0), chunk.data)
    return path


def link_recording(path: Path, megabytes: float, chunk_bytes: int = 64, seed: int = 1) -> Path:
    """An intact recording of ``megabytes`` of link bytes in small chunks (a serial port's reads), one per ms."""
    data = np.random.default_rng(seed).integers(0, 256, int(megabytes * 2**20), dtype=np.uint8).tobytes()
    with RecordingWriter(path, {"source": "crafted"}) as writer:
        for i, start in enumerate(range(0, len(data), chunk_bytes)):
            writer.write_chunk(i * 1_000_000, data[start:start + chunk_bytes])
    return path


# Files that cost time or memory out of proportion if read naively; not in CRAFTED, since a replay
# paces across a chunk time jump in real time.
HUGE = {"false_markers": false_markers, "sparse_zeros": sparse_zeros, "chunk_time_jump": chunk_time_jump}


if __name__ == "__main__":
    for name, path in write_all(Path(sys.argv[1])).items():
        print(name, path)
    for name, make in HUGE.items():
        print(name, make(Path(sys.argv[1]), name))


def damaged_csv_gz(folder: Path, name: str = "damaged") -> Path:
    """A dataset CSV, gzip-compressed, with 40 bytes of its deflate stream inverted (zlib.error on reading)."""
    import gzip

    rows = 2000
    columns = {"time_s": np.arange(rows) / 100.0, **{f"gyr_{a}_rad_s": np.zeros(rows) for a in "xyz"},
               **{f"acc_{a}_m_s2": np.full(rows, 9.81 if a == "z" else 0.0) for a in "xyz"}}
    text = ",".join(columns) + "\n" + "\n".join(",".join(f"{columns[c][i]:.6f}" for c in columns) for i in range(rows))
    data = bytearray(gzip.compress(text.encode()))
    data[30:70] = bytes(b ^ 0xFF for b in data[30:70])
    path = folder / f"{name}.csv.gz"
    path.write_bytes(bytes(data))
    return path


def dataset_csv(folder: Path, name: str = "trial", rows: int = 2000, rate_hz: float = 100.0) -> Path:
    """A dataset CSV at rest (1 g on z), ``rows`` rows from t = 0 at ``rate_hz``."""
    columns = {"time_s": np.arange(rows) / rate_hz, **{f"gyr_{a}_rad_s": np.zeros(rows) for a in "xyz"},
               **{f"acc_{a}_m_s2": np.full(rows, 9.81 if a == "z" else 0.0) for a in "xyz"}}
    path = folder / f"{name}.csv"
    path.write_text(",".join(columns) + "\n" + "\n".join(",".join(repr(float(columns[c][i])) for c in columns)
                                                        for i in range(rows)) + "\n")
    return path


def first_samples_block_damaged(recording: Path) -> Path:
    """The imported recording with one byte of its first samples block's values inverted (its CRC fails)."""
    data = bytearray(recording.read_bytes())
    header = data.find(b'{"columns"')
    data[header + 200] ^= 0xFF
    recording.write_bytes(bytes(data))
    return recording


def byte_range_duplicated(recording: Path, start_fraction: float = 0.3, length_fraction: float = 0.1) -> Path:
    """The recording with a range of its bytes written twice (a copy tool that retried a block): the
    repeated range holds whole records, with their valid CRCs, and is cut anywhere."""
    data = recording.read_bytes()
    start, length = int(len(data) * start_fraction), int(len(data) * length_fraction)
    recording.write_bytes(data[:start + length] + data[start:start + length] + data[start + length:])
    return recording


def forged_config_recording(folder: Path, name: str = "forged", at_s: float = 4.0, duration_s: float = 8.0,
                            firmware=None, events=(), **changes) -> Path:
    """A simulated hover (±4 g, ±500 °/s) with one extra CONFIG chunk at ``at_s`` saying ``changes`` (e.g.
    ``accel_fs_g=16``): a forged or corrupted CONFIG from another sender, its checksum valid. ``events``:
    (t_host_ns, event) recorded as well (a live session's answer to the held CONFIG)."""
    from firmware_protocol import encode, make_frame
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.sim.firmware import FirmwareSettings

    stream = SimStream(Scenario(profile="hover", duration_s=duration_s, seed=3, firmware=firmware or FirmwareSettings()))
    chunks = [(round(c.t_s * 1e9), c.data) for c in [*stream.advance(stream.end_s), *stream.flush()]]
    probe = Pipeline(())
    for t_ns, data in chunks:
        probe.feed(t_ns, data)
        if probe.config is not None:
            break
    forged = encode(make_frame("CONFIG", 0, **{**probe.config, **changes}))
    at = next(i for i, (t_ns, _) in enumerate(chunks) if t_ns >= at_s * 1e9)
    chunks.insert(at, (chunks[at][0], forged))
    path = folder / f"{name}.gsrec"
    with RecordingWriter(path, {"source": "crafted", "filters": ["ahf"]}) as writer:
        for t_ns, data in chunks:
            writer.write_chunk(t_ns, data)
        for t_ns, event in events:
            writer.write_event(t_ns, event)
    return path


# -- Flight logs whose names and texts are hostile (issues 31 and 37): written with the tests' own ULog and
# DataFlash writers (tests/autopilot/mavlink_helpers.py), each a short flight that loads plus what is crafted.

def ulog_topics(path: Path, topics: list[str], logged: list[tuple[int, int, str]] = ()) -> dict[str, int]:
    """A 2 s PX4 flight (``px4_flight``) plus one topic per name of ``topics`` (the i-th with 10 (i + 1) rows, 10 ms apart,
    of a float ``value``) and ``logged`` messages (time µs, syslog level, text); returns topic -> rows."""
    from tests.autopilot.mavlink_helpers import BOOT_US, px4_flight, write_ulog

    flight, _ = px4_flight(duration_s=2.0)
    extra = {}
    for i, name in enumerate(topics):
        rows = 10 * (i + 1)
        extra[name] = ([("uint64_t", "timestamp"), ("float", "value")],
                       {"timestamp": BOOT_US + 10_000 * np.arange(rows), "value": np.full(rows, float(i))})
    write_ulog(path, {**flight, **extra}, logged=list(logged))
    return {name: 10 * (i + 1) for i, name in enumerate(topics)}


def dataflash_types(path: Path, types: list[str], messages: list[str] = ()) -> dict[str, int]:
    """A 2 s DataFlash log of IMU and ATT at 50 Hz plus one type per name of ``types`` (the i-th with
    10 (i + 1) rows of a float ``Value``) and a MSG per text of ``messages``; returns type -> rows."""
    from tests.autopilot.mavlink_helpers import write_dataflash

    time_us = 20_000_000 + 20_000 * np.arange(100)
    written = {"IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", [(int(t), 0, 0.0, 0.0, 0.0, 0.0, 0.0, -9.8) for t in time_us]),
               "ATT": ("Qfff", "TimeUS,Roll,Pitch,Yaw", [(int(t), 0.0, 0.0, 0.0) for t in time_us])}
    for i, name in enumerate(types):
        written[name] = ("Qf", "TimeUS,Value", [(int(t), float(i)) for t in time_us[: 10 * (i + 1)]])
    if messages:
        written["MSG"] = ("QZ", "TimeUS,Message", [(int(time_us[10 + k]), text.encode()) for k, text in enumerate(messages)])
    write_dataflash(path, written)
    return {name: 10 * (i + 1) for i, name in enumerate(types)}

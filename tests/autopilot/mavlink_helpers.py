"""Shared by the autopilot tests: MAVLink streams made with pymavlink's own encoder, a ULog file
written byte by byte from the ULog format specification, and where the shared flight logs live."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

FLIGHTLOGS = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs"


def flightlog(name: str) -> Path:
    """The shared log ``name``, or skip with the reason."""
    import pytest

    path = FLIGHTLOGS / name
    if not path.is_file():
        pytest.skip(f"shared flight log {name} not present in {FLIGHTLOGS.resolve()} (../shared/datasets/flightlogs)")
    return path


class Sender:
    """One MAVLink sender: pack with its own sequence numbers, as ``MAVLink.send`` does."""

    def __init__(self, system: int = 1, component: int = 1, mavlink1: bool = False):
        self.encoder = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.mavlink1 = mavlink1

    def pack(self, msg) -> bytes:
        data = msg.pack(self.encoder, self.mavlink1)
        self.encoder.seq = (self.encoder.seq + 1) % 256
        return data

    def __getattr__(self, name):  # sender.heartbeat(...) -> bytes
        encode = getattr(self.encoder, f"{name}_encode")
        return lambda *args: self.pack(encode(*args))


def ardupilot_heartbeat(sender: Sender) -> bytes:
    return sender.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED, 5, mavlink.MAV_STATE_ACTIVE)


# -- ULog (https://docs.px4.io/main/en/dev_log/ulog_file_format.html) ------------------------------

ULOG_TYPES = {"uint64_t": "Q", "float": "f", "uint8_t": "B", "int32_t": "i"}


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path, topics: dict[str, tuple[list[tuple[str, str]], dict[str, np.ndarray]]], info: dict[str, str] | None = None) -> None:
    """``topics``: name -> (fields [(type, name)], columns name -> (N,) or (N, k) array). Version 1 file
    with the flag-bits message, one format and one subscription per topic, data interleaved by time."""
    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", 0))
    out += _message(b"B", bytes(16) + struct.pack("<3Q", 0, 0, 0))
    for key, value in (info or {}).items():
        name = f"char[{len(value)}] {key}".encode()
        out += _message(b"I", bytes([len(name)]) + name + value.encode())
    rows = []
    for msg_id, (topic, (fields, columns)) in enumerate(topics.items()):
        spec = "".join(f"{ftype} {fname};" for ftype, fname in fields)
        out += _message(b"F", f"{topic}:{spec}".encode())
    for msg_id, (topic, (fields, columns)) in enumerate(topics.items()):
        out += _message(b"A", struct.pack("<BH", 0, msg_id) + topic.encode())
        codes = [ULOG_TYPES[ftype.split("[")[0]] for ftype, _ in fields]
        counts = [int(ftype.split("[")[1][:-1]) if "[" in ftype else 1 for ftype, _ in fields]
        fmt = "<" + "".join(f"{n}{c}" for c, n in zip(codes, counts))
        for i in range(len(columns["timestamp"])):
            values = []
            for (_, fname), code in zip(fields, codes):
                cast = float if code == "f" else int
                values.extend(cast(v) for v in np.atleast_1d(columns[fname][i]).tolist())
            rows.append((int(columns["timestamp"][i]), msg_id, struct.pack(fmt, *values)))
    for _, msg_id, payload in sorted(rows, key=lambda r: (r[0], r[1])):
        out += _message(b"D", struct.pack("<H", msg_id) + payload)
    Path(path).write_bytes(bytes(out))

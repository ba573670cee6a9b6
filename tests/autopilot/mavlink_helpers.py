"""Shared by the autopilot tests: MAVLink streams made with pymavlink's own encoder, a ULog file
written byte by byte from the ULog format specification, and where the shared flight logs live."""

from __future__ import annotations

import struct
import threading
import time
from pathlib import Path

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation import geodesy
from groundstation.autopilot.streams import pack_next
from groundstation.sim.profiles import make_profile

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
        return pack_next(self.encoder, msg, self.mavlink1)

    def __getattr__(self, name):  # sender.heartbeat(...) -> bytes
        encode = getattr(self.encoder, f"{name}_encode")
        return lambda *args: self.pack(encode(*args))


def ardupilot_heartbeat(sender: Sender) -> bytes:
    return sender.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_SAFETY_ARMED, 5, mavlink.MAV_STATE_ACTIVE)


# -- ULog (https://docs.px4.io/main/en/dev_log/ulog_file_format.html) ------------------------------

ULOG_TYPES = {"uint64_t": "Q", "float": "f", "uint8_t": "B", "int32_t": "i", "int16_t": "h", "uint32_t": "I"}


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path, topics: dict[str, tuple[list[tuple[str, str]], dict[str, np.ndarray]]], info: dict[str, str] | None = None,
               logged: list[tuple[int, int, str]] = ()) -> None:
    """``topics``: name -> (fields [(type, name)], columns name -> (N,) or (N, k) array). Version 1 file
    with the flag-bits message, one format and one subscription per topic, data interleaved by time;
    ``logged``: logged messages (timestamp µs, syslog level 0-7, text) among them."""
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
            rows.append((int(columns["timestamp"][i]), msg_id, b"D", struct.pack("<H", msg_id) + struct.pack(fmt, *values)))
    for timestamp, level, text in logged:
        rows.append((timestamp, -1, b"L", struct.pack("<BQ", ord("0") + level, timestamp) + text.encode()))
    for _, _, kind, payload in sorted(rows, key=lambda r: (r[0], r[1])):
        out += _message(kind, payload)
    Path(path).write_bytes(bytes(out))


BOOT_US = 5_000_000


def px4_flight(duration_s=12.0, imu_hz=200, att_hz=50):
    """A PX4-like log of the simulator's flight profile: ideal IMU, its truth as both vehicle_attitude and
    the SITL ground truth, GPS every 40 IMU samples; returns (topics for ``write_ulog``, IMU-rate truth)."""
    profile = make_profile("flight", duration_s, seed=4)
    t_imu = np.arange(int(duration_s * imu_hz)) / imu_hz
    truth = profile.truth(t_imu)
    t_att = np.arange(int(duration_s * att_hz)) / att_hz
    att = profile.truth(t_att).q_body_to_ned
    sensor_combined = ([("uint64_t", "timestamp"), ("float[3]", "gyro_rad"), ("float[3]", "accelerometer_m_s2")],
                       {"timestamp": BOOT_US + np.rint(t_imu * 1e6), "gyro_rad": truth.rate_body_rad_s,
                        "accelerometer_m_s2": truth.specific_force_body_m_s2()})
    attitude = ([("uint64_t", "timestamp"), ("float[4]", "q")], {"timestamp": BOOT_US + np.rint(t_att * 1e6), "q": att})
    t_gps = t_imu[::40]
    lat, lon, alt = geodesy.geodetic_from_ned(profile.truth(t_gps).pos_ned_m, (47.0, 8.0, 400.0))
    vel = profile.truth(t_gps).vel_ned_m_s
    gps = ([("uint64_t", "timestamp"), ("int32_t", "lat"), ("int32_t", "lon"), ("int32_t", "alt"), ("float", "vel_n_m_s"),
            ("float", "vel_e_m_s"), ("float", "vel_d_m_s"), ("uint8_t", "fix_type"), ("uint8_t", "satellites_used")],
           {"timestamp": BOOT_US + np.rint(t_gps * 1e6), "lat": np.rint(lat * 1e7), "lon": np.rint(lon * 1e7), "alt": np.rint(alt * 1000),
            "vel_n_m_s": vel[:, 0], "vel_e_m_s": vel[:, 1], "vel_d_m_s": vel[:, 2], "fix_type": np.full(len(t_gps), 3),
            "satellites_used": np.full(len(t_gps), 11)})  # fmt: skip
    return {"sensor_combined": sensor_combined, "vehicle_attitude": attitude, "vehicle_attitude_groundtruth": attitude,
            "vehicle_gps_position": gps}, truth  # fmt: skip


# -- ArduPilot DataFlash (.bin): records "A3 95 id payload", formats declared by FMT (id 128) records --

def dataflash_record(msg_id: int, payload: bytes) -> bytes:
    return b"\xa3\x95" + bytes([msg_id]) + payload


DATAFLASH_STRUCT = {"n": "4s", "N": "16s", "Z": "64s", "a": "32h"}  # DataFlash format characters that are not struct's


def dataflash_struct(fmt: str) -> str:
    return "<" + "".join(DATAFLASH_STRUCT.get(c, c) for c in fmt)


def dataflash_fmt(msg_id: int, name: str, fmt: str, labels: str) -> bytes:
    length = 3 + struct.calcsize(dataflash_struct(fmt))
    return dataflash_record(128, struct.pack("<BB4s16s64s", msg_id, length, name.encode(), fmt.encode(), labels.encode()))


def write_dataflash(path, messages: dict[str, tuple[str, str, list[tuple]]]) -> None:
    """``messages``: name -> (DataFlash format of the fields, labels, rows); rows of all types are written
    in order of their first field (TimeUS); an ``a`` field (int16[32]) takes 32 values of the row."""
    out = bytearray(dataflash_fmt(128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"))
    rows = []
    for msg_id, (name, (fmt, labels, values)) in enumerate(messages.items(), start=130):
        out += dataflash_fmt(msg_id, name, fmt, labels)
        rows += [(row[0], msg_id, struct.pack(dataflash_struct(fmt), *row)) for row in values]
    for _, msg_id, payload in sorted(rows, key=lambda r: r[:2]):
        out += dataflash_record(msg_id, payload)
    Path(path).write_bytes(bytes(out))


def free_udp_port() -> int:
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class Flying:
    """A simulated aircraft's bridge (pty or UDP) streaming in a thread for the ``with`` block; closed after."""

    def __init__(self, bridge):
        import threading

        self.bridge = bridge
        self._stop = threading.Event()
        self._thread = threading.Thread(target=bridge.run, args=(self._stop.is_set,), daemon=True)

    def __enter__(self):
        self._thread.start()
        return self.bridge

    def __exit__(self, *exc_info) -> None:
        self._stop.set()
        self._thread.join()
        self.bridge.close()


def pty_session(aircraft, seconds: float, **session_options):
    """A live session of ``aircraft`` through a real pseudo-terminal (bridge-sim's), run for ``seconds``
    and stopped; ``session_options`` go to ``open_session``."""
    from groundstation.session_makers.factory import open_session
    from groundstation.sim.pty_bridge import PtyBridge

    bridge = PtyBridge(aircraft)
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        session = open_session(f"mavlink:{bridge.path}?baud=57600", **session_options)
        with session:
            time.sleep(seconds)
    finally:
        stop.set()
        thread.join()
        bridge.close()
    return session


def live_aiding_stage(stream, readings, q, acc_g, dt_s, samples: int):
    """The live session's aiding stage (``Aiding``, driven as ``pipeline`` drives it, one call per reading
    and sample) over a log's merged events (``stream``, ``readings``: ``session_makers.flight_log_session._Readings``)
    with the aiding estimator's attitudes ``q``: what each sample hands the estimators (mag, GPS fix
    rows, NaN for none), the headings, the samples with a position row and the rows."""
    from groundstation.session_parts import aiding

    stage = aiding.Aiding()
    mag, fix = np.full((samples, 3), np.nan), np.full((samples, 4), np.nan)
    heading, at, rows = [np.nan] * len(readings.mag_body), [], []
    latest = None
    gps = [dict(zip(readings.gps_values, row)) for row in zip(*(v.tolist() for v in readings.gps_values.values()))]
    for kind, i in zip(*(part.tolist() for part in stream)):
        if kind == aiding.SAMPLE:
            body, taken = stage.take_for_estimators()
            if body is not None:
                mag[i] = body
            if taken is not None:
                fix[i] = taken
            latest = q[i].tolist()
            if stage.position_on:
                at.append(i)
                rows.append(stage.position_step(acc_g[i].tolist(), latest, float(dt_s[i])))
        elif kind == aiding.MAG:
            heading[i] = stage.magnetometer(tuple(readings.mag_body[i].tolist()), latest)
        elif kind == aiding.BARO:
            stage.barometer(float(readings.pressure_pa[i]))
        elif kind == aiding.GPS:
            stage.gps(gps[i])
        elif kind == aiding.RESTART:
            stage.restart()
    return mag, fix, np.array(heading), np.array(at, dtype=int), np.array(rows).reshape(-1, 6)

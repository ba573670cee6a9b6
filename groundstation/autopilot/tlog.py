"""The ``.tlog`` file Mission Planner and QGroundControl write and open: each MAVLink packet as
received, preceded by its receive time as an 8-byte big-endian count of µs since 1970.

Reading walks that layout (packet length from its header: MAVLink 1 ``0xFE``, MAVLink 2 ``0xFD``, with
signature) and lets pymavlink decode and check each packet; where the bytes do not fit (junk, a
truncated end), it resynchronises on the next plausible timestamp followed by a packet start.

A session opens a ``.tlog`` as the live link it was: its packets at their receive times through the
pipeline's MAVLink front-end (``session_packets``, ``session_makers.loaders.tlog``, ``sources.mavlink``). One rule
first: a log whose autopilot clock advanced, over its later half, more than its receive clock by more than the session
clock lets a frame arrive early (``SessionClock``'s ``JUMP_TOLERANCE_S`` plus ``DRIFT_TOLERANCE`` of the
time elapsed) has *compressed* receive times (SITL autotests log 308 s of autopilot time in 12 s);
no live link delivers that, so its packets are stamped on the autopilot's clock instead (each at the
autopilot time reached so far; a reboot holds it, so the session still sees the reboot).
"""

from __future__ import annotations

import dataclasses
import struct
from array import array
from collections import defaultdict
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from firmware_protocol.decoder import BACK_TOLERANCE_US

from groundstation.autopilot import records as rec
from groundstation.autopilot.decoder import MavlinkDecoder, new_parser
from groundstation.autopilot.flightlog import GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, Series, cut_message, series
from groundstation.autopilot.imu_choice import ImuChoice, said_choice
from groundstation.autopilot.mapping import (
    MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_AUTOPILOT_INVALID, MAV_AUTOPILOT_PX4, PRESSURE_TYPES, SCALED_IMU_TYPES, MessageMapper,
)
from groundstation.errors import UserError
from groundstation.autopilot.vehicle import Vehicle
from groundstation.session_parts.clock import DRIFT_TOLERANCE, JUMP_TOLERANCE_S

STAMP = struct.Struct(">Q")
MAGIC_V1, MAGIC_V2 = 0xFE, 0xFD
SIGNED = 0x01
RESYNC_WINDOW_US = 3 * 24 * 3600 * 1_000_000  # a timestamp this far from the last is junk
UNIX_RANGE_US = (946_684_800_000_000, 4_102_444_800_000_000)  # 2000-01-01 .. 2100-01-01
AUTOPILOT_NAMES = {MAV_AUTOPILOT_ARDUPILOTMEGA: "ArduPilot", MAV_AUTOPILOT_PX4: "PX4"}


def packet_length(data, at: int) -> int | None:
    """Length of the packet starting at ``at`` from its header, None if no packet starts there."""
    if at + 3 > len(data):
        return None
    magic, payload = data[at], data[at + 1]
    if magic == MAGIC_V1:
        return payload + 8
    if magic == MAGIC_V2:
        return payload + 12 + (13 if data[at + 2] & SIGNED else 0)
    return None


UNFINISHED = b""  # packets(): the file ends inside this record


def packets(data: bytes) -> Iterator[tuple[int, bytes | None]]:
    """(receive time µs since 1970, packet bytes) in file order; ``(skipped_bytes, None)`` for junk, and
    last ``(its bytes, UNFINISHED)`` when the file ends inside a record (a cut log)."""
    for stamp_us, start, stop in _records(data):
        yield stamp_us, (data[start:stop] if stop is not None else start)


def _records(data: bytes) -> Iterator[tuple[int, int | bytes | None, int | None]]:
    """``packets`` as places in ``data``: (receive time µs, start, stop) of each packet; junk and the
    unfinished end as ``packets`` says them, with a stop of None."""
    at, last_us, end = 0, None, len(data)
    while at + 8 < end:
        (stamp_us,) = STAMP.unpack_from(data, at)
        length = packet_length(data, at + 8)
        plausible = _plausible(stamp_us, last_us)
        if length is not None and plausible and at + 8 + length <= end:
            yield stamp_us, at + 8, at + 8 + length
            last_us, at = stamp_us, at + 8 + length
            continue
        if length is not None and plausible:  # a record that runs past the end
            yield end - at, UNFINISHED, None
            return
        start = at
        at += 1
        while at + 8 < end and not _looks_like_record(data, at, last_us):
            at += 1
        if at + 8 >= end:  # junk to the end
            at = end
        yield at - start, None, None
    if at < end:  # a record cut inside its receive time
        yield end - at, UNFINISHED, None


def _looks_like_record(data, at: int, last_us: int | None) -> bool:
    return data[at + 8] in (MAGIC_V1, MAGIC_V2) and _plausible(STAMP.unpack_from(data, at)[0], last_us)


def _plausible(stamp_us: int, last_us: int | None) -> bool:
    """A receive time: a date this century, within days of the previous record's."""
    in_range = UNIX_RANGE_US[0] <= stamp_us <= UNIX_RANGE_US[1]
    return in_range and (last_us is None or abs(stamp_us - last_us) <= RESYNC_WINDOW_US)


def messages(path, progress=None) -> Iterator[tuple[int, object]]:
    """(receive time µs since 1970, pymavlink message) of every valid packet, and (skipped byte count,
    None) for each run of junk or packet that fails its check."""
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        raise UserError(f"{path}: cannot read ({error.strerror})") from None
    parser = new_parser()
    for i, (stamp_us, packet) in enumerate(packets(data)):
        if progress is not None and i % 8192 == 0:
            progress(i, max(len(data) // 40, i + 1))  # ~40 B per record
        if not packet:
            yield stamp_us, None
            continue
        try:
            yield stamp_us, parser.decode(bytearray(packet))
        except Exception:  # pymavlink raises MAVError (CRC, unknown id) and struct.error (short payload)
            yield len(packet) + 8, None


class Packets:
    """(receive time ns, packet bytes) of a log's packets in file order, as a sequence: kept as the file's
    bytes and columns of places and times (a list of tuples of bytes took ~4x the file), each packet's
    bytes cut when it is asked."""

    def __init__(self, data: bytes, starts: np.ndarray, stops: np.ndarray, times_ns: np.ndarray):
        self._data, self._starts, self._stops, self.times_ns = data, starts, stops, times_ns

    def __len__(self) -> int:
        return len(self.times_ns)

    def __getitem__(self, i: int) -> tuple[int, bytes]:
        return int(self.times_ns[i]), self._data[self._starts[i] : self._stops[i]]

    def __iter__(self) -> Iterator[tuple[int, bytes]]:
        data, block = self._data, 4096  # places as Python ints a block at a time (~40 bytes each: a small block)
        for first in range(0, len(self), block):
            rows = slice(first, first + block)
            for t_ns, start, stop in zip(self.times_ns[rows].tolist(), self._starts[rows].tolist(), self._stops[rows].tolist()):
                yield t_ns, data[start:stop]

    def __eq__(self, other) -> bool:
        return len(self) == len(other) and all(a == b for a, b in zip(self, other))


@dataclasses.dataclass
class SessionPackets:
    """A ``.tlog``'s packets as a session receives them: (receive time ns, packet) in file order."""

    packets: Packets
    bad_bytes: int  # bytes between the records, skipped
    bad_runs: int
    compressed: bool  # receive times replaced by the autopilot's clock (the module's rule)
    unfinished_bytes: int = 0  # of the record the file ends inside

    def notes(self) -> list[str]:
        out = [f"{self.bad_runs} damaged byte runs ({self.bad_bytes} bytes) skipped"] if self.bad_runs else []
        if self.unfinished_bytes:
            out.append(cut_message(self.unfinished_bytes))
        if self.compressed:
            out.append("receive times compressed (the autopilot clock runs faster): timed by the autopilot clock")
        return out


def session_packets(data: bytes) -> SessionPackets:
    """The packets of a ``.tlog``'s bytes with the receive times a session feeds them at."""
    data = bytes(data)
    # 8 bytes a number (a list of Python ints took 36: three times the file for a log of short packets)
    stamps, starts, stops, bad_bytes, bad_runs, unfinished = array("q"), array("q"), array("q"), 0, 0, 0
    for stamp_us, start, stop in _records(data):
        if start is UNFINISHED:
            unfinished = stamp_us
        elif start is None:
            bad_bytes, bad_runs = bad_bytes + stamp_us, bad_runs + 1
        else:  # a packet that fails its check is the decoder's to count, as on a live link
            stamps.append(stamp_us)
            starts.append(start)
            stops.append(stop)
    stamped = Packets(data, np.frombuffer(starts, dtype=np.int64), np.frombuffer(stops, dtype=np.int64),
                      np.frombuffer(stamps, dtype=np.int64) * 1000)
    del stamps, starts, stops
    on_autopilot = _autopilot_clock(stamped)
    compressed = on_autopilot is not None
    if compressed:
        stamped.times_ns = on_autopilot
    return SessionPackets(stamped, bad_bytes, bad_runs, compressed, unfinished)


# The messages whose records time the autopilot clock or choose the vehicle (``Vehicle.choose``): the
# clock decodes these only (a fifth of a log's packets: the session decodes every packet again after it)
_CLOCK_MESSAGE_IDS = frozenset(getattr(mavlink, f"MAVLINK_MSG_ID_{name}") for name in (
    "HEARTBEAT", "RAW_IMU", "HIGHRES_IMU", "ATTITUDE", "ATTITUDE_QUATERNION", *SCALED_IMU_TYPES, *PRESSURE_TYPES))


def _message_id(packet: bytes) -> int:
    """The message id in a whole packet's header (MAVLink 1: one byte; 2: three, little-endian)."""
    return packet[5] if packet[0] == MAGIC_V1 else int.from_bytes(packet[7:10], "little")


def _autopilot_clock(stamped: Packets) -> np.ndarray | None:
    """Each packet's time on the vehicle's clock (ns from the first packet's receive time: the autopilot
    time reached so far), if the log's receive times are compressed; else None. Judged over the log's
    later half by receive time: a live link's backlog at the start (bytes queued before the session
    read them) arrives "compressed" too, and is no reason to distrust the receive clock."""
    decoder, vehicle = MavlinkDecoder(), Vehicle()  # the front-end's choice of the vehicle
    reached_us, latest_us, times = 0, None, array("q")
    for t_ns, packet in stamped:
        if decoder.idle and _message_id(packet) not in _CLOCK_MESSAGE_IDS:  # (its records neither time nor choose)
            times.append(reached_us)
            continue
        for r in decoder.feed(packet, t_ns):
            vehicle.choose(r)
            timed = isinstance(r, (rec.ImuSample, rec.OnboardAttitude, rec.MagReading, rec.BaroReading))
            if timed and vehicle.sent(r) and r.time_us is not None:
                if latest_us is not None and r.time_us > latest_us:
                    reached_us += r.time_us - latest_us
                if latest_us is None or r.time_us > latest_us or r.time_us < latest_us - BACK_TOLERANCE_US:
                    latest_us = r.time_us  # forward, or back further than a late sensor: a reboot
        times.append(reached_us)
    if not stamped:
        return None
    # The first packet received at the midpoint or later: a search, not a bisection, since receive times
    # need not be in order (a clock that runs backwards); the first or the last packet always qualifies.
    middle_ns = (stamped[0][0] + stamped[-1][0]) / 2
    half = next(i for i, (t_ns, _) in enumerate(stamped) if t_ns >= middle_ns)
    receive_s = (stamped[-1][0] - stamped[half][0]) * 1e-9
    autopilot_s = (times[-1] - times[half]) * 1e-6
    if autopilot_s <= receive_s + JUMP_TOLERANCE_S + DRIFT_TOLERANCE * autopilot_s:
        return None
    return stamped[0][0] + np.frombuffer(times, dtype=np.int64) * 1000


def read_tlog(path, progress=None) -> FlightLog:
    mapper = MessageMapper()
    records, bad_bytes, bad_runs = [], 0, 0
    for stamp_us, msg in messages(path, progress):
        if msg is None:
            bad_bytes, bad_runs = bad_bytes + stamp_us, bad_runs + 1
            continue
        records.extend(mapper.map(msg, stamp_us * 1000))
    if not records:
        raise UserError(f"{path}: no MAVLink messages found; not a .tlog, or damaged from the start")
    log = from_records(Path(path), records, mapper)
    if bad_runs:
        log.notes.append(f"{bad_runs} damaged or unparseable byte runs ({bad_bytes} bytes) skipped")
    return log


def from_records(path: Path, records: list, mapper: MessageMapper) -> FlightLog:
    """The records of one vehicle (the first system whose heartbeat names an autopilot) as arrays."""
    systems = list(mapper.autopilot)
    system = systems[0] if systems else _busiest_system(records)
    autopilot = AUTOPILOT_NAMES.get(mapper.autopilot.get(system), f"MAV_AUTOPILOT {mapper.autopilot.get(system)}")
    mine = [r for r in records if r.system == system]
    log = FlightLog(path, "tlog", autopilot)
    if not systems:
        log.notes.append("no autopilot heartbeat: RAW_IMU units unknown, kept as a generic table")
    device_us = _device_clock(mine)
    by_kind = defaultdict(list)
    for r in mine:
        by_kind[type(r)].append(r)
    choice = ImuChoice()
    rows = [r for r in by_kind[rec.ImuSample] if choice.take(r.source, r.acc_g)]
    if rows:
        log.imu = series([r.time_us for r in rows], dict(zip(IMU_COLUMNS, np.column_stack(
            [[r.gyr_rad_s for r in rows], [r.acc_g for r in rows]]).T)), choice.chosen)  # fmt: skip
        mags = [r for r in by_kind[rec.MagReading] if r.source == choice.chosen]
        if mags and np.any([r.mag_uT for r in mags]):
            log.mag = series([r.time_us for r in mags], dict(zip(MAG_COLUMNS, np.array([r.mag_uT for r in mags]).T)), choice.chosen)
    said_choice(log, choice)
    attitude = by_kind[rec.OnboardAttitude]
    sources = {r.source for r in attitude}
    board_source = "ATTITUDE_QUATERNION" if "ATTITUDE_QUATERNION" in sources else "ATTITUDE"
    rows = [r for r in attitude if r.source == board_source]
    log.onboard = series([r.time_us for r in rows], dict(zip(Q_COLUMNS, np.array([r.q for r in rows]).reshape(-1, 4).T)), board_source)
    baro = [r for r in by_kind[rec.BaroReading] if r.source in ("HIGHRES_IMU", "SCALED_PRESSURE")]
    log.baro = series([r.time_us for r in baro], {"pressure_hpa": [r.pressure_hpa for r in baro],
                                                  "temperature_c": [r.temperature_c for r in baro]}, "SCALED_PRESSURE")  # fmt: skip
    fixes = [r for r in by_kind[rec.GpsReading] if r.fix_type >= 2 and r.time_us > 0]
    log.gps = series([r.time_us for r in fixes], {c: [getattr(r, c) for r in fixes] for c in GPS_COLUMNS}, "GPS_RAW_INT")
    log.tables, log.units = _tables(mine, by_kind, device_us)
    modes = list(dict.fromkeys(r.mode for r in by_kind[rec.VehicleStatus] if r.autopilot != MAV_AUTOPILOT_INVALID))
    if modes:
        log.notes.append(f"modes: {', '.join(modes)}")
    return log


def _busiest_system(records) -> int:
    counts = defaultdict(int)
    for r in records:
        counts[r.system] += 1
    return max(counts, key=counts.get)


def _device_clock(records):
    """Host ns -> autopilot µs, interpolated between the messages that carry both (for those that carry
    only the host time); None when no message carries a device time."""
    pairs = sorted((r.t_host_ns, r.time_us) for r in records if getattr(r, "time_us", None))
    if not pairs:
        return None
    host, device = np.array(pairs, dtype=float).T
    device = np.maximum.accumulate(device)
    return lambda t_host_ns: np.interp(t_host_ns, host, device)


def _tables(mine, by_kind, device_us) -> tuple[dict[str, Series], dict[str, dict[str, str]]]:
    """Every other message as a table per type, and link health, battery and status as the live session
    keeps them (``records.RECORD_TABLES``), on the device clock."""
    if device_us is None:
        return {}, {}
    tables, units = {}, {}
    generic = defaultdict(list)
    for r in by_kind[rec.GenericMessage]:
        generic[r.msg_type].append(r)
    for name, rows in generic.items():
        fields = list(rows[0].fields)
        own = np.array([r.time_us or 0 for r in rows], dtype=float)
        times = np.where(own > 0, own, device_us(np.array([r.t_host_ns for r in rows], dtype=float)))
        values = np.array([list(r.fields.values()) for r in rows], dtype=float).reshape(len(rows), len(fields))  # one layout per type
        tables[name] = series(times, dict(zip(fields, values.T)), name)
        units[name] = dict(rows[0].units)
    for kind, (name, _, columns) in rec.RECORD_TABLES.items():
        rows = by_kind[kind]
        if rows:
            tables[name] = series(device_us(np.array([r.t_host_ns for r in rows], dtype=float)),
                                  {field: [float(getattr(r, a)) for r in rows] for a, (field, _) in columns.items()}, name)
            units[name] = rec.table_fields(kind)[3]
    return tables, units


def write_tlog(path, packets_with_time: Iterable[tuple[int, bytes]]) -> int:
    """Write (unix time µs, raw packet) pairs as a .tlog; returns the number of packets written."""
    count = 0
    try:
        with open(path, "xb") as out:
            for stamp_us, packet in packets_with_time:
                out.write(STAMP.pack(int(stamp_us)) + bytes(packet))
                count += 1
    except FileExistsError:
        raise UserError(f"{path} exists; choose another name") from None
    except OSError as error:
        raise UserError(f"cannot write {path}: {error.strerror}") from None
    return count


def packets_of_chunks(chunks: Iterable[tuple[int, bytes]], unix_us_at_first: int) -> Iterator[tuple[int, bytes]]:
    """A byte stream's packets, each stamped with the arrival time of the chunk that completed it
    (chunks: (host monotonic ns, bytes), as a recording holds them) on the unix clock."""
    parser = new_parser()
    t0_ns = None
    for t_host_ns, data in chunks:
        t0_ns = t_host_ns if t0_ns is None else t0_ns
        stamp_us = unix_us_at_first + (t_host_ns - t0_ns) // 1000
        for msg in parser.parse_buffer(data) or ():
            if msg.get_type() != "BAD_DATA":
                yield stamp_us, msg.get_msgbuf()


def recording_to_tlog(recording, out) -> int:
    """A recorded MAVLink session (raw bytes with arrival times) as a standard .tlog: each packet
    stamped with the wall-clock time its bytes arrived (the recording's ``start_utc`` plus the
    monotonic time since it opened). Returns the number of packets; UserError if there are none."""
    from datetime import datetime

    if recording.metadata.get("protocol", "gs") != "mavlink":
        # Bytes of the project's own frames can pass MAVLink's framing by chance: never write them as packets.
        raise UserError(f"{recording.path} is a recording of this project's own telemetry, not of a MAVLink link: "
                        "a .tlog holds MAVLink only (export writes CSV or Parquet)")
    if recording.chunk_count == 0:
        raise UserError(f"{recording.path}: the recording holds no link bytes")
    first_ns = int(recording.chunk_t_host_ns[0])
    start = recording.metadata.get("start_utc")
    unix_us = int(datetime.fromisoformat(start).timestamp() * 1e6) if start else 0
    if start and recording.t_open_ns is not None:
        unix_us += (first_ns - recording.t_open_ns) // 1000
    packets = list(packets_of_chunks(recording.chunks(), unix_us))
    if not packets:
        raise UserError(f"{recording.path}: holds no MAVLink packets (a recording of this project's own protocol?)")
    return write_tlog(out, packets)

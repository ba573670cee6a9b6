"""ArduPilot DataFlash ``.bin`` logs through pymavlink's ``DFReader`` (the autopilot's own clock: ``TimeUS``,
or ``TimeMS`` in logs of ArduPilot before 3.3, 2015, whose ``GPS`` carries its boot time in ``T`` ms
and GPS time of week in ``TimeMS``).

Messages and units used (ArduPilot's LogStructure): ``IMU`` (the instance ``I`` with real samples first,
``imu_choice``: ``GyrX..Z`` rad/s,
``AccX..Z`` m/s², body FRD, every sample the logging rate keeps), ``ATT`` (``Roll``, ``Pitch``, ``Yaw`` in
degrees, ZYX, body -> NED: the onboard estimate), ``MAG`` (instance 0, ``MagX..Z`` mGauss), ``BARO``
(instance 0, ``Press`` Pa, ``Temp`` °C), ``GPS`` (instance 0: ``Lat``/``Lng`` degrees, ``Alt`` m,
``Spd`` m/s, ``GCrs`` degrees, ``VZ`` m/s down, ``Status`` fix type, ``NSats``). A log whose logging
bitmask left out ``IMU`` still opens, with the onboard attitude only. ``MSG``, ``ERR``, ``EV``, ``MODE``,
``ARM`` and ``PARM``: what the autopilot said and how it was set (``messages.dataflash_said``), each at its
own boot time, or (a log before 2015: no time in ``PARM``, ``MSG``, ``MODE``, ``EV``) at the latest record's
that has one, as DFReader times them.
"""

from __future__ import annotations

import itertools
import math
from array import array
from collections import defaultdict

import numpy as np
from pymavlink import DFReader

from groundstation import quaternion
from groundstation.autopilot.chatter import Chatter
from groundstation.autopilot.imu_choice import ImuChoice, said_choice
from groundstation.autopilot.logtables import CLOCKS, DataflashTables
from groundstation.autopilot.flightlog import (
    GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, cut_message, gps_unix_us, series, utc_offset_us,
)
from groundstation.autopilot.messages import DATAFLASH_SAID, dataflash_said
from groundstation.errors import UserError
from groundstation.formats import FORMATS
from groundstation.units import STANDARD_GRAVITY_M_S2

MAGIC = FORMATS["dataflash"].magic  # every DataFlash record starts with these two bytes
FIELDS = {  # each row: the time in µs (``CLOCKS``), then these
    "IMU": ("GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ"),
    "ATT": ("Yaw", "Pitch", "Roll"),
    "MAG": ("MagX", "MagY", "MagZ"),
    "BARO": ("Press", "Temp"),
    "GPS": ("Lat", "Lng", "Alt", "Spd", "GCrs", "VZ", "Status", "NSats"),
}
IMU_TYPES = ("IMU", "IMU2", "IMU3")  # an IMU: instance ``I`` of IMU, or (logs before 2015) a type of its own
MGAUSS_TO_UT = 0.1
# A log copied off the card or flash in whole blocks (an SD card's 512-byte sectors; ArduPilot's file logger
# writes 4 KiB at a time) ends mid-record, in its last block: a file of whole blocks whose unfinished
# record is shorter than one is that, not damage (both shared real .bin logs end so).
BLOCK_BYTES = 512

def read_dataflash(path, progress=None) -> FlightLog:
    with open(path, "rb") as f:
        if f.read(2) != MAGIC:
            raise UserError(f"{path}: not an ArduPilot DataFlash log (it does not start with 0xA3 0x95)")
    said, gps_times = [], []
    taken, taken_type = defaultdict(lambda: array("q")), {}  # FIELDS kind -> its rows' file offsets; their type
    choice = ImuChoice()  # the IMU instance the estimators run on
    every = DataflashTables()  # every message type as a table (``logtables``)
    chatter = Chatter()  # DFReader prints a "bad header" line per damaged byte, some from C: counted, not shown
    try:
        with chatter.caught():
            reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
        cut = unfinished_record_bytes(reader)  # from DFReader's index of every record, which then goes: it holds a
        reader.offsets = None  # Python int per record (as much memory as the file), and reading on (recv_msg) needs none
        clocks = {name: boot_clock(reader, name) for name in reader.name_to_id}
        last_us = None  # the boot time of the latest stamped record: an unstamped one (a log before 2015's PARM, MSG) came then
        with chatter.caught(descriptors=False):  # reading prints from Python only
            for count in itertools.count():
                if (msg := reader.recv_msg()) is None:
                    break
                start = reader.offset - msg.fmt.len  # DFReader stands at the record's end
                every.add(msg, start)
                name = msg.get_type()
                if name == "GPS" and getattr(msg, "GWk", 0) > 0 and getattr(msg, "TimeUS", None) is not None:
                    gps_times.append((msg.GWk, msg.GMS, msg.TimeUS))  # any instance: the GPS time is one
                if (clock := clocks.get(name)) is not None:
                    last_us = getattr(msg, clock[0]) * clock[1]
                if name in DATAFLASH_SAID:
                    said.append((last_us, msg))
                elif clock is not None and (kind := "IMU" if name in IMU_TYPES else name) in FIELDS and _taken(msg, name, choice):
                    taken[kind].append(start)
                    taken_type[kind] = name  # one type a kind: the IMU's rows are its chosen stream's
                if progress is not None and count % 4096 == 0:
                    progress(reader.percent, 100)
    except RecursionError:  # DFReader reads on by calling itself once per record that does not fit its FMT
        raise UserError(f"{path}: cannot read this DataFlash log: a thousand records in a row do not fit the lengths "
                        "their formats (FMT) declare; damaged, or not a DataFlash log") from None
    except Exception as error:  # DFReader raises assorted errors on corrupt formats
        raise UserError(f"{path}: cannot read this DataFlash log ({error})") from None
    log = FlightLog(path, "dataflash", "ArduPilot")
    first_us = next((t_us for t_us, _ in said if t_us is not None), 0)  # what came before any stamp: the log's start
    log.events, log.parameters = dataflash_said([(first_us if t_us is None else int(t_us), r) for t_us, r in said], reader.mav_type)
    log.parameter_defaults = {r.Name: float(r.Default) for _, r in said  # ArduPilot 4.3's PARM on: NaN when not known
                              if r.get_type() == "PARM" and not math.isnan(getattr(r, "Default", math.nan))}
    said.clear()  # DFReader's messages: a Python object per value
    if gps_times:
        week, ms, boot_us = np.array(gps_times, dtype=np.int64).T
        log.utc_offset_us, log.utc_source = utc_offset_us(gps_unix_us(week, ms), boot_us), "GPS week and ms (GWk, GMS)"
    skipped = [line.split()[1] for line in chatter.lines if line.startswith("Skipped ")]  # "Skipped N bad bytes ..."
    # The same damaged bytes, counted twice: once a "bad header" each while DFReader indexes the file, once
    # as "Skipped N bad bytes" while it reads the messages; either pass may see them.
    damaged = max(chatter.count("bad header"), sum(int(n) for n in skipped if n.isdigit()))
    if damaged:
        log.damage.append(f"{damaged} damaged bytes skipped")
    if cut and reader.data_len % BLOCK_BYTES == 0 and cut < BLOCK_BYTES:
        log.notes.append(f"the log ends in its last block with {cut} bytes of a record the autopilot had not finished: "
                         "a log copied off the card in whole blocks ends so")
    elif cut:
        log.damage.append(cut_message(cut))
    data = np.frombuffer(reader.data_map, dtype=np.uint8)  # the file's bytes (mapped: not copied)
    # DFReader is read: it goes before the tables are made (its latest message of each type and its metadata
    # point back at it; without those cycles it goes now, not at the garbage collector's next pass)
    reader.messages.clear()
    reader.metadata = None
    del reader
    try:
        rows = {kind: every.fields(data, taken_type[kind], starts, FIELDS[kind]) for kind, starts in taken.items()}
    except ValueError as error:
        raise UserError(f"{path}: cannot read this DataFlash log ({error})") from None
    _streams(log, rows, choice)
    log.tables, log.units, log.warnings = every.tables(data)
    return log


def _streams(log: FlightLog, rows: dict[str, np.ndarray], choice: ImuChoice) -> None:
    """The log's ``imu``, ``onboard``, ``mag``, ``baro`` and ``gps`` from ``rows``: per ``FIELDS`` kind, the time
    and the fields of the records taken."""
    if (imu := rows.get("IMU")) is not None:
        values = np.column_stack([imu[:, 1:4], imu[:, 4:7] / STANDARD_GRAVITY_M_S2])
        log.imu = series(imu[:, 0], dict(zip(IMU_COLUMNS, values.T)), choice.chosen)
    else:
        log.notes.append(f"{choice.said()}: onboard attitude only" if choice.heard else
                         "no IMU messages logged (the logging bitmask left them out): onboard attitude only")
    if (att := rows.get("ATT")) is not None:
        q = quaternion.from_euler_zyx(*np.radians(att[:, 1:4]).T)
        log.onboard = series(att[:, 0], dict(zip(Q_COLUMNS, q.T)), "ATT")
    if (mag := rows.get("MAG")) is not None:
        log.mag = series(mag[:, 0], dict(zip(MAG_COLUMNS, (mag[:, 1:4] * MGAUSS_TO_UT).T)), "MAG[0]")
    if (baro := rows.get("BARO")) is not None:
        log.baro = series(baro[:, 0], {"pressure_hpa": baro[:, 1] / 100.0, "temperature_c": baro[:, 2]}, "BARO[0]")
    said_choice(log, choice)
    gps = rows.get("GPS", np.zeros((0, 1 + len(FIELDS["GPS"]))))  # the time, then the fields
    gps = gps[gps[:, 7] >= 2]  # a 2D fix or better
    if len(gps):
        course = np.radians(gps[:, 5])
        columns = [gps[:, 1], gps[:, 2], gps[:, 3], gps[:, 4] * np.cos(course), gps[:, 4] * np.sin(course), gps[:, 6], gps[:, 7], gps[:, 8]]
        log.gps = series(gps[:, 0], dict(zip(GPS_COLUMNS, columns)), "GPS[0]")


def _taken(msg, name: str, choice: ImuChoice) -> bool:
    """Whether a sensor message is the session's: the IMU ``choice`` takes, instance 0 of the others."""
    if name not in IMU_TYPES:
        return getattr(msg, "I", 0) == 0
    return choice.take(f"IMU[{getattr(msg, 'I', 0)}]" if name == "IMU" else name, (msg.AccX / STANDARD_GRAVITY_M_S2, msg.AccY / STANDARD_GRAVITY_M_S2,
                                                        msg.AccZ / STANDARD_GRAVITY_M_S2))


def boot_clock(reader, name: str) -> tuple[str, int] | None:
    """(field, µs per unit) of the boot clock in message ``name``'s format; None if the log has no such message."""
    fmt = next((f for f in reader.formats.values() if f.name == name), None)
    if fmt is None:
        return None
    return next(((field, scale) for field, scale in CLOCKS if field in fmt.columns), None)


def unfinished_record_bytes(reader) -> int:
    """Bytes at the end of the file that start a record and stop before its end (a cut log), else 0.
    Trailing bytes that start no record (a block-based log's unused page) do not count."""
    starts = [(offsets[-1], mtype) for mtype, offsets in enumerate(reader.offsets) if offsets and mtype in reader.formats]
    if not starts:
        return 0
    start, mtype = max(starts)
    end = start + reader.formats[mtype].len
    if end > reader.data_len:  # the last record indexed runs past the end
        return reader.data_len - start
    tail = reader.data_map[end : end + 2]
    return reader.data_len - end if len(tail) and tail == MAGIC[: len(tail)] else 0

"""ArduPilot DataFlash ``.bin`` logs through pymavlink's ``DFReader`` (the autopilot's own clock, ``TimeUS``).

Messages and units used (ArduPilot's LogStructure): ``IMU`` (instance ``I`` 0: ``GyrX..Z`` rad/s,
``AccX..Z`` m/s², body FRD, every sample the logging rate keeps), ``ATT`` (``Roll``, ``Pitch``, ``Yaw`` in
degrees, ZYX, body -> NED: the onboard estimate), ``MAG`` (instance 0, ``MagX..Z`` mGauss), ``BARO``
(instance 0, ``Press`` Pa, ``Temp`` °C), ``GPS`` (instance 0: ``Lat``/``Lng`` degrees, ``Alt`` m,
``Spd`` m/s, ``GCrs`` degrees, ``VZ`` m/s down, ``Status`` fix type, ``NSats``). A log whose logging
bitmask left out ``IMU`` still opens, with the onboard attitude only. ``MSG``, ``ERR``, ``EV``, ``MODE``,
``ARM`` and ``PARM``: what the autopilot said and how it was set (``messages.dataflash_said``).
"""

from __future__ import annotations

import contextlib
import io
import itertools
from collections import defaultdict

import numpy as np
from pymavlink import DFReader

from groundstation import quaternion
from groundstation.autopilot.logtables import DataflashTables
from groundstation.autopilot.flightlog import GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, series
from groundstation.autopilot.messages import DATAFLASH_SAID, dataflash_said
from groundstation.errors import UserError
from groundstation.formats import FORMATS
from groundstation.units import STANDARD_GRAVITY_M_S2

MAGIC = FORMATS["dataflash"].magic  # every DataFlash record starts with these two bytes
FIELDS = {
    "IMU": ("TimeUS", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ"),
    "ATT": ("TimeUS", "Yaw", "Pitch", "Roll"),
    "MAG": ("TimeUS", "MagX", "MagY", "MagZ"),
    "BARO": ("TimeUS", "Press", "Temp"),
    "GPS": ("TimeUS", "Lat", "Lng", "Alt", "Spd", "GCrs", "VZ", "Status", "NSats"),
}
MGAUSS_TO_UT = 0.1


def read_dataflash(path, progress=None) -> FlightLog:
    with open(path, "rb") as f:
        if f.read(2) != MAGIC:
            raise UserError(f"{path}: not an ArduPilot DataFlash log (it does not start with 0xA3 0x95)")
    rows, said = defaultdict(list), []
    every = DataflashTables()  # every message type as a table (``logtables``)
    chatter = io.StringIO()  # DFReader prints "bad header" lines for damaged bytes: counted, not shown
    try:
        with contextlib.redirect_stdout(chatter):
            reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
            for count in itertools.count():
                if (msg := reader.recv_msg()) is None:
                    break
                every.add(msg)
                if msg.get_type() in DATAFLASH_SAID:
                    said.append(msg)
                elif msg.get_type() in FIELDS and getattr(msg, "I", 0) == 0:  # instance 0 of the multi-instance sensors
                    rows[msg.get_type()].append([getattr(msg, f) for f in FIELDS[msg.get_type()]])
                if progress is not None and count % 4096 == 0:
                    progress(reader.percent, 100)
    except Exception as error:  # DFReader raises assorted errors on corrupt formats
        raise UserError(f"{path}: cannot read this DataFlash log ({error})") from None
    log = FlightLog(path, "dataflash", "ArduPilot")
    log.events, log.parameters = dataflash_said(said, reader.mav_type)
    log.tables, log.units = every.tables()
    damaged = chatter.getvalue().count("bad header")
    if damaged:
        log.notes.append(f"{damaged} damaged bytes skipped")
    if rows["IMU"]:
        imu = np.array(rows["IMU"], dtype=float)
        values = np.column_stack([imu[:, 1:4], imu[:, 4:7] / STANDARD_GRAVITY_M_S2])
        log.imu = series(imu[:, 0], dict(zip(IMU_COLUMNS, values.T)), "IMU[0]")
    else:
        log.notes.append("no IMU messages logged (the logging bitmask left them out): onboard attitude only")
    if rows["ATT"]:
        att = np.array(rows["ATT"], dtype=float)
        q = quaternion.from_euler_zyx(*np.radians(att[:, 1:4]).T)
        log.onboard = series(att[:, 0], dict(zip(Q_COLUMNS, q.T)), "ATT")
    if rows["MAG"]:
        mag = np.array(rows["MAG"], dtype=float)
        log.mag = series(mag[:, 0], dict(zip(MAG_COLUMNS, (mag[:, 1:4] * MGAUSS_TO_UT).T)), "MAG[0]")
    if rows["BARO"]:
        baro = np.array(rows["BARO"], dtype=float)
        log.baro = series(baro[:, 0], {"pressure_hpa": baro[:, 1] / 100.0, "temperature_c": baro[:, 2]}, "BARO[0]")
    gps = np.array(rows["GPS"], dtype=float).reshape(-1, len(FIELDS["GPS"]))
    gps = gps[gps[:, 7] >= 2]  # a 2D fix or better
    if len(gps):
        course = np.radians(gps[:, 5])
        columns = [gps[:, 1], gps[:, 2], gps[:, 3], gps[:, 4] * np.cos(course), gps[:, 4] * np.sin(course), gps[:, 6], gps[:, 7], gps[:, 8]]
        log.gps = series(gps[:, 0], dict(zip(GPS_COLUMNS, columns)), "GPS[0]")
    return log

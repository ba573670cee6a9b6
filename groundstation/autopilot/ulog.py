"""PX4 ``.ulg`` logs through ``pyulog`` (the autopilot's clock, ``timestamp`` µs since boot).

Topics used, first instance: ``sensor_combined`` (``gyro_rad[3]`` rad/s, ``accelerometer_m_s2[3]``,
body FRD, full rate; logs before ~2018 also carry ``magnetometer_ga[3]`` there), ``vehicle_attitude``
(``q[4]`` w-first body -> NED: the onboard estimate), ``vehicle_magnetometer`` (``magnetometer_ga[3]``),
``vehicle_air_data`` (``baro_pressure_pa``) or ``sensor_baro`` (``pressure``: hPa up to PX4 1.12, Pa
after), ``vehicle_gps_position`` (``lat``/``lon`` 1e-7 degrees and ``alt`` mm, or ``latitude_deg``/
``longitude_deg``/``altitude_msl_m`` from PX4 1.14; ``vel_{n,e,d}_m_s``), and in SITL logs
``vehicle_attitude_groundtruth`` (the simulator's true attitude, kept as truth); ``vehicle_status``
(``nav_state``, ``arming_state``), the logged messages and parameters: ``messages.ulog_said``.

pyulog parses the file once. A plain file (``plain_chain``: the usual one) it reads through its own
buffered file, at its own speed; a damaged one, or one cut inside a message, through ``LastRead``,
which says what of the last message there is. Every topic becomes a table (``logtables``).
"""

from __future__ import annotations

import io

import numpy as np
from pyulog import ULog

from groundstation.estimation.compiled_cache import use_user_cache

use_user_cache()  # before numba is imported: the walk below is compiled once per user, as the estimators are
from numba import njit  # noqa: E402

from groundstation.autopilot.chatter import Chatter
from groundstation.autopilot.flightlog import (
    GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, cut_message, implausible_message, implausible_times, series, utc_offset_us,
)
from groundstation.autopilot.logtables import ulog_tables
from groundstation.autopilot.messages import ulog_said
from groundstation.errors import UserError
from groundstation.formats import FORMATS
from groundstation.units import STANDARD_GRAVITY_M_S2

MAGIC = FORMATS["ulog"].magic
GAUSS_TO_UT = 100.0
SYSTEM_DEFAULTS = 0  # pyulog's default_type: the firmware's defaults (1: the airframe's)


def read_ulog(path, progress=None) -> FlightLog:
    with open(path, "rb") as f:
        if f.read(7) != MAGIC:
            raise UserError(f"{path}: not a PX4 ULog file (it does not start with 'ULog')")
    chatter = Chatter()  # pyulog prints what it finds damaged: kept as a note
    handle = None
    try:
        with chatter.caught(descriptors=False):
            if plain_chain(np.fromfile(path, dtype=np.uint8)):  # (numba caches no kernel for a read-only mapping)
                ulog = ULog(str(path))  # every topic: each is a table (``logtables``)
            else:
                with open(path, "rb") as raw:
                    handle = LastRead(raw)
                    ulog = ULog(handle)
    except Exception as error:  # pyulog raises ULogException and struct/index errors on damaged files
        raise UserError(f"{path}: cannot read this ULog file ({error})") from None
    log = FlightLog(path, "ulog", ulog.msg_info_dict.get("sys_name", "PX4"))
    if ulog.file_corruption:
        log.damage.append("damaged bytes: pyulog found records it could not read and skipped to the next sync; "
                          "the messages in them are missing")
    if handle is not None and handle.unfinished_bytes:
        log.damage.append(cut_message(handle.unfinished_bytes))
    topics = {}
    for data in ulog.data_list:
        if len(data.data["timestamp"]):
            wild = implausible_times(data.data["timestamp"])
            if wild.any():
                log.damage.append(implausible_message(data.name, data.data["timestamp"][wild]))
                data.data = {name: values[~wild] for name, values in data.data.items()}
            if data.multi_id == 0:
                topics[data.name] = data.data
    log.notes += chatter.lines
    _streams(log, topics, ulog)
    del topics  # the streams are made: each topic's buffer goes once its table is (``ulog_tables``)
    log.tables, log.units, log.warnings = ulog_tables(ulog.data_list)
    return log


def _streams(log: FlightLog, topics: dict, ulog: ULog) -> None:
    """The log's ``imu``, ``onboard``, ``truth``, ``mag``, ``baro``, ``gps``, its UTC offset, events and parameters
    from ``topics`` (the first instance of each: pyulog's columns by field)."""
    if (sc := topics.get("sensor_combined")) is not None:
        values = [*(sc[f"gyro_rad[{i}]"] for i in range(3)), *(sc[f"accelerometer_m_s2[{i}]"] / STANDARD_GRAVITY_M_S2 for i in range(3))]
        log.imu = series(sc["timestamp"], dict(zip(IMU_COLUMNS, values)), "sensor_combined")
    else:
        log.notes.append("no sensor_combined topic: onboard attitude only")
    for topic, target in (("vehicle_attitude", "onboard"), ("vehicle_attitude_groundtruth", "truth")):
        if (att := topics.get(topic)) is not None:
            setattr(log, target, series(att["timestamp"], {c: att[f"q[{i}]"] for i, c in enumerate(Q_COLUMNS)}, topic))
    mag_topic = next((t for t in ("vehicle_magnetometer", "sensor_combined") if "magnetometer_ga[0]" in topics.get(t, {})), None)
    if mag_topic is not None:
        mag = topics[mag_topic]
        log.mag = series(mag["timestamp"], {c: mag[f"magnetometer_ga[{i}]"] * GAUSS_TO_UT for i, c in enumerate(MAG_COLUMNS)}, mag_topic)
    log.baro = _baro(topics)
    log.gps = _gps(topics.get("vehicle_gps_position"))
    gps = topics.get("vehicle_gps_position", {})
    if "time_utc_usec" in gps and (fixed := gps["time_utc_usec"] > 0).any():  # 0: no GPS time yet
        log.utc_offset_us = utc_offset_us(gps["time_utc_usec"][fixed], gps["timestamp"][fixed])
        log.utc_source = "vehicle_gps_position.time_utc_usec"
    log.events, log.parameters = ulog_said(ulog, topics.get("vehicle_status"))
    if ulog.has_default_parameters:  # PX4 1.12 on: the system default of each parameter not at it (Flight Review's)
        logged = ulog.get_default_parameters(SYSTEM_DEFAULTS)
        log.parameter_defaults = {name: float(logged.get(name, value)) for name, value in ulog.initial_parameters.items()}


def _baro(topics):
    if (air := topics.get("vehicle_air_data")) is not None and "baro_pressure_pa" in air:
        return series(air["timestamp"], {"pressure_hpa": air["baro_pressure_pa"] / 100.0,
                                         "temperature_c": air.get("baro_temp_celcius", np.full(len(air["timestamp"]), np.nan))},
                      "vehicle_air_data")  # fmt: skip
    if (baro := topics.get("sensor_baro")) is not None:
        pressure = baro["pressure"].astype(float)
        if np.nanmedian(pressure) > 2000.0:  # Pa (PX4 1.13 on) rather than hPa
            pressure = pressure / 100.0
        return series(baro["timestamp"], {"pressure_hpa": pressure, "temperature_c": baro["temperature"]}, "sensor_baro")
    return None


def _gps(gps):
    if gps is None:
        return None
    if "latitude_deg" in gps:
        lat, lon, alt = gps["latitude_deg"], gps["longitude_deg"], gps["altitude_msl_m"]
    else:
        lat, lon, alt = gps["lat"] * 1e-7, gps["lon"] * 1e-7, gps["alt"] / 1000.0
    fix = gps["fix_type"] >= 2
    columns = [lat, lon, alt, gps["vel_n_m_s"], gps["vel_e_m_s"], gps["vel_d_m_s"], gps["fix_type"], gps["satellites_used"]]
    return series(gps["timestamp"][fix], {c: np.asarray(v, dtype=float)[fix] for c, v in zip(GPS_COLUMNS, columns)}, "vehicle_gps_position")


HEADER_BYTES = 16  # the file header: magic, version, start time
APPENDED_DATA = 1  # bit 0 of the flag bits' first incompatible byte: data appended at given offsets
# Message types pyulog reads where they stand, without seeking: in the definitions (any type whose
# header is sound: unknown ones are skipped whole) and after them (``_read_file_data``: any other
# type makes it search for a sync sequence). The definitions end at the first of ``DATA_START``.
DATA_START = np.zeros(256, dtype=np.bool_)
DATA_START[[ord(c) for c in "ALC"]] = True
DATA_TYPES = np.zeros(256, dtype=np.bool_)
DATA_TYPES[[ord(c) for c in "IMPQALCDOS"]] = True
MAX_SOUND_SIZE = 10000  # a larger message, or one of size or type 0, is corruption to pyulog


def plain_chain(data: np.ndarray) -> bool:
    """Whether pyulog reads the file ``data`` (its bytes) message after message to its very end: every
    header sound, no type that makes it search for a sync sequence, no data appended, and the last
    message ending with the file. Only then does its reading end on an empty header read, with nothing
    unfinished; so a plain file needs no ``LastRead`` (a Python call per read, a third of pyulog's own
    time) and pyulog reads it through its own buffered file."""
    first = HEADER_BYTES
    if len(data) >= first + 3 + 9 and data[first + 2] == ord("B") and data[first + 3 + 8] & APPENDED_DATA:
        return False
    return _walk(data, first, DATA_START, DATA_TYPES, MAX_SOUND_SIZE)


@njit(cache=True)
def _walk(data, position, data_start, data_types, max_size):  # pragma: no cover - compiled
    in_data = False
    while position + 3 <= len(data):
        size = data[position] | (np.int64(data[position + 1]) << 8)
        kind = data[position + 2]
        if kind == 0 or size == 0 or size > max_size:
            return False
        in_data = in_data or data_start[kind]
        if in_data and not data_types[kind]:
            return False
        position += 3 + size
    return position == len(data)


class LastRead(io.RawIOBase):
    """The file pyulog reads, watched for how its reading ended. pyulog reads each message as its 3-byte
    header, then the payload the header announces, and stops at the first read that comes back short.
    A file that ends between two messages ends on an empty header read; any other short read is a
    message the file stops inside (``unfinished_bytes``: what there was of it)."""

    def __init__(self, raw):
        super().__init__()
        self.raw = raw
        self.unfinished_bytes = 0
        self._header = 0  # bytes of the last full 3-byte read: a header whose payload comes next

    def read(self, size=-1):
        data = self.raw.read(size)
        if size is not None and 0 <= len(data) < size:
            self.unfinished_bytes = len(data) + self._header if (data or self._header) else 0
        self._header = 3 if size == 3 and len(data) == 3 else 0
        return data

    def readable(self):
        return True

    def seekable(self):
        return True

    def seek(self, offset, whence=io.SEEK_SET):
        return self.raw.seek(offset, whence)

    def tell(self):
        return self.raw.tell()

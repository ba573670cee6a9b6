"""One pymavlink message -> records in this project's units (``records``), per autopilot.

Units, from the MAVLink common and ardupilotmega definitions:

| message | acc | gyro | mag | pressure | time |
|---|---|---|---|---|---|
| ``SCALED_IMU``, ``SCALED_IMU2``, ``SCALED_IMU3`` (any autopilot) | mG | mrad/s | mgauss | | ``time_boot_ms`` |
| ``RAW_IMU`` from ArduPilot | mG | mrad/s | mgauss | | ``time_usec`` (since boot) |
| ``RAW_IMU`` from any other autopilot | raw ADC counts, scale unknown: kept as a generic message only | | | | |
| ``HIGHRES_IMU`` (PX4) | m/s² | rad/s | gauss | hPa | ``time_usec`` |
| ``SCALED_PRESSURE``, ``2``, ``3`` | | | | hPa (temperature c°C) | ``time_boot_ms`` |

ArduPilot fills ``RAW_IMU`` with the already calibrated, scaled IMU 0 (the same units as
``SCALED_IMU``), and ``SCALED_IMU2``/``3`` with IMUs 1 and 2; PX4 sends ``HIGHRES_IMU``. Which
autopilot a system is comes from its ``HEARTBEAT`` (``autopilot`` 3 ArduPilot, 12 PX4): a ``RAW_IMU``
before the first heartbeat of its system is kept as a generic message. 1 gauss = 100 µT; g here is
standard gravity (9.80665 m/s²). Axes need no change: both autopilots report body FRD and body -> NED.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from pymavlink import mavutil

from groundstation import quaternion
from groundstation.autopilot.records import (
    Battery,
    BaroReading,
    GenericMessage,
    GpsReading,
    ImuSample,
    LinkHealth,
    MagReading,
    OnboardAttitude,
    ParamValue,
    StatusText,
    VehicleStatus,
)
from groundstation.units import STANDARD_GRAVITY_M_S2

MAV_AUTOPILOT_ARDUPILOTMEGA = 3
MAV_AUTOPILOT_PX4 = 12
MAV_AUTOPILOT_INVALID = 8  # "not an autopilot"
MAV_MODE_FLAG_SAFETY_ARMED = 128

# IMU messages in milli-units: (acc g per unit, gyro rad/s per unit, mag µT per unit)
MILLI_SCALES = (1e-3, 1e-3, 0.1)
SCALED_IMU_TYPES = ("SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3")
PRESSURE_TYPES = ("SCALED_PRESSURE", "SCALED_PRESSURE2", "SCALED_PRESSURE3")
UINT16_UNKNOWN = 65535
# MAV_PARAM_TYPE -> struct format of an integer PX4 copies byte for byte into PARAM_VALUE's float
MAVLINK1_HEADER, MAVLINK2_HEADER = 6, 10  # bytes before the payload (magic 0xFE, 0xFD)
PX4_INTEGER_FORMATS = {1: "<B", 2: "<b", 3: "<H", 4: "<h", 5: "<I", 6: "<i"}


@dataclass
class SenderCounts:
    """Per (system, component): messages received and lost (gaps in the 8-bit sequence number).

    A message out of its sender's sequence is held (``_broke``) until the next one says what it was: if
    the sequence goes on from it, the messages between were lost; if the sequence goes on from before it,
    it was a stranger using the sender's ids (a spoofer, another link's copy) and nothing was lost to it
    (counted in ``strangers``). Counted blindly, each stranger made up to 255 of the sender's messages
    look lost on its way in and again on its way out."""

    received: int = 0
    lost: int = 0
    strangers: int = 0
    last_seq: int | None = None
    _broke: int | None = None  # the sequence number of a message out of sequence, not yet judged

    def count(self, seq: int) -> None:
        self.received += 1
        if self.last_seq is not None and self._broke is not None:
            from_last, from_broke = (seq - self.last_seq - 1) % 256, (seq - self._broke - 1) % 256
            if from_last < from_broke:  # the sequence goes on from before the break: that was a stranger
                self.strangers += 1
                self.received -= 1
            else:  # it goes on from the break: the messages before the break were lost
                self.lost += (self._broke - self.last_seq - 1) % 256
                self.last_seq = self._broke
            self._broke = None
        if self.last_seq is None or (seq - self.last_seq - 1) % 256 == 0:
            self.last_seq = seq
        else:
            self._broke = seq

    @property
    def loss_pct(self) -> float:
        total = self.received + self.lost
        return 100.0 * self.lost / total if total else 0.0


def device_time_us(msg) -> int | None:
    """The autopilot's own time of a message, µs since boot, when it carries one."""
    usec = getattr(msg, "time_usec", None)
    if usec is not None:
        return int(usec)
    boot_ms = getattr(msg, "time_boot_ms", None)
    return None if boot_ms is None else int(boot_ms) * 1000


def centi_temperature(value: int) -> float:
    """c°C; 0 means "not provided" in MAVLink (a sensor at 0 °C sends 1)."""
    return value / 100.0 if value else math.nan


class MessageMapper:
    """Turns messages into records; keeps per-sender autopilot types and sequence counts."""

    def __init__(self):
        self.autopilot: dict[int, int] = {}  # system id -> MAV_AUTOPILOT from its heartbeat
        self.senders: dict[tuple[int, int], SenderCounts] = {}
        self._handlers = {
            "HEARTBEAT": self._heartbeat, "SYS_STATUS": self._sys_status, "RADIO_STATUS": self._radio,
            "RAW_IMU": self._raw_imu, "HIGHRES_IMU": self._highres_imu,
            "ATTITUDE": self._attitude, "ATTITUDE_QUATERNION": self._attitude_quaternion,
            "GPS_RAW_INT": self._gps, "STATUSTEXT": self._statustext, "PARAM_VALUE": self._param_value,
            **{name: self._scaled_imu for name in SCALED_IMU_TYPES},
            **{name: self._pressure for name in PRESSURE_TYPES},
        }  # fmt: skip

    def map(self, msg, t_host_ns: int = 0) -> list:
        """Records for one message (parsed by pymavlink); bad data gives none."""
        msg_type = msg.get_type()
        if msg_type == "BAD_DATA":
            return []
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        self.senders.setdefault(sender, SenderCounts()).count(msg.get_seq())
        handler = self._handlers.get(msg_type)
        records = handler(msg, sender, t_host_ns) if handler is not None else None
        return records if records is not None else [generic(msg, sender, t_host_ns)]

    # -- handlers: each returns records, or None to keep the message as a generic one -------------

    def _heartbeat(self, msg, sender, t_host_ns):
        if msg.autopilot != MAV_AUTOPILOT_INVALID:  # a GCS, camera or companion on the same system id
            self.autopilot[sender[0]] = msg.autopilot
        armed = bool(msg.base_mode & MAV_MODE_FLAG_SAFETY_ARMED)
        return [VehicleStatus(*sender, t_host_ns, msg.autopilot, msg.type, mavutil.mode_string_v10(msg), armed,
                              msg.system_status, msg.custom_mode)]  # fmt: skip

    def _statustext(self, msg, sender, t_host_ns):
        """The text as a record of its own, and the numbers (severity, id, chunk) as a row of ``statustext``."""
        return [generic(msg, sender, t_host_ns), StatusText(*sender, t_host_ns, msg.severity, msg.text, msg.id, msg.chunk_seq)]

    def _param_value(self, msg, sender, t_host_ns):
        buffer = bytes(msg.get_msgbuf())
        payload = buffer[MAVLINK2_HEADER if buffer[:1] == b"\xfd" else MAVLINK1_HEADER :]
        value = param_value(payload, msg.param_value, msg.param_type, self.autopilot.get(sender[0]))
        return [generic(msg, sender, t_host_ns), ParamValue(*sender, t_host_ns, msg.param_id, value)]

    def _sys_status(self, msg, sender, t_host_ns):
        voltage = msg.voltage_battery / 1000.0 if msg.voltage_battery != UINT16_UNKNOWN else math.nan
        current = msg.current_battery / 100.0 if msg.current_battery != -1 else math.nan
        remaining = float(msg.battery_remaining) if msg.battery_remaining != -1 else math.nan
        return [Battery(*sender, t_host_ns, voltage, current, remaining, msg.drop_rate_comm / 100.0, msg.errors_comm)]

    def _radio(self, msg, sender, t_host_ns):
        return [LinkHealth(*sender, t_host_ns, msg.rssi, msg.remrssi, msg.noise, msg.remnoise, msg.rxerrors, msg.fixed, msg.txbuf)]

    def _raw_imu(self, msg, sender, t_host_ns):
        if self.autopilot.get(sender[0]) != MAV_AUTOPILOT_ARDUPILOTMEGA:
            return None  # raw counts of an unknown scale
        return self._milli_imu(msg, sender, t_host_ns)

    def _scaled_imu(self, msg, sender, t_host_ns):
        return self._milli_imu(msg, sender, t_host_ns)

    def _milli_imu(self, msg, sender, t_host_ns):
        acc_scale, gyr_scale, mag_scale = MILLI_SCALES
        time_us, source = device_time_us(msg), msg.get_type()
        return [
            ImuSample(*sender, t_host_ns, time_us, source,
                      (msg.xgyro * gyr_scale, msg.ygyro * gyr_scale, msg.zgyro * gyr_scale),
                      (msg.xacc * acc_scale, msg.yacc * acc_scale, msg.zacc * acc_scale), centi_temperature(msg.temperature)),
            MagReading(*sender, t_host_ns, time_us, source, (msg.xmag * mag_scale, msg.ymag * mag_scale, msg.zmag * mag_scale)),
        ]  # fmt: skip

    def _highres_imu(self, msg, sender, t_host_ns):
        g = STANDARD_GRAVITY_M_S2
        time_us, source = msg.time_usec, "HIGHRES_IMU"
        return [
            ImuSample(*sender, t_host_ns, time_us, source, (msg.xgyro, msg.ygyro, msg.zgyro),
                      (msg.xacc / g, msg.yacc / g, msg.zacc / g), float(msg.temperature)),
            MagReading(*sender, t_host_ns, time_us, source, (msg.xmag * 100.0, msg.ymag * 100.0, msg.zmag * 100.0)),
            BaroReading(*sender, t_host_ns, time_us, source, float(msg.abs_pressure), float(msg.temperature)),
        ]  # fmt: skip

    def _pressure(self, msg, sender, t_host_ns):
        return [BaroReading(*sender, t_host_ns, device_time_us(msg), msg.get_type(), float(msg.press_abs), centi_temperature(msg.temperature))]

    def _attitude(self, msg, sender, t_host_ns):
        q = quaternion.from_euler_zyx(msg.yaw, msg.pitch, msg.roll)
        return [OnboardAttitude(*sender, t_host_ns, device_time_us(msg), "ATTITUDE", tuple(q.tolist()))]

    def _attitude_quaternion(self, msg, sender, t_host_ns):
        q = (msg.q1, msg.q2, msg.q3, msg.q4)  # MAVLink: q1 is w, body -> NED
        return [OnboardAttitude(*sender, t_host_ns, device_time_us(msg), "ATTITUDE_QUATERNION", q)]

    def _gps(self, msg, sender, t_host_ns):
        speed = msg.vel / 100.0 if msg.vel != UINT16_UNKNOWN else math.nan
        course = math.radians(msg.cog / 100.0) if msg.cog != UINT16_UNKNOWN else math.nan
        satellites = msg.satellites_visible if msg.satellites_visible != 255 else -1
        return [generic(msg, sender, t_host_ns),  # its fix's quality (eph: HDOP) as a row of ``gps_raw_int``
                GpsReading(*sender, t_host_ns, msg.time_usec, msg.lat * 1e-7, msg.lon * 1e-7, msg.alt / 1000.0,
                           speed * math.cos(course), speed * math.sin(course), math.nan, msg.fix_type, satellites)]  # fmt: skip


def param_value(payload: bytes, value: float, param_type: int, autopilot: int | None) -> float:
    """A PARAM_VALUE's number: a PX4 integer from the float's 4 bytes (the start of the payload, exact
    where a float conversion could not keep a NaN pattern's bits), every other value as sent (ArduPilot
    converts its integers to the float; an autopilot not yet heard is taken as doing so)."""
    fmt = PX4_INTEGER_FORMATS.get(param_type)
    if autopilot != MAV_AUTOPILOT_PX4 or fmt is None or len(payload) < 4:
        return float(value)
    return float(struct.unpack_from(fmt, payload)[0])


def generic(msg, sender, t_host_ns) -> GenericMessage:
    """Numeric fields (arrays flattened as ``name_i``), with pymavlink's units where it has them."""
    scalars, arrays, units = _layout(msg)
    fields = {name: getattr(msg, name) for name in scalars}
    for name, flat in arrays:
        fields.update(zip(flat, getattr(msg, name)))
    return GenericMessage(*sender, t_host_ns, device_time_us(msg), msg.get_type(), fields, units)


# message type -> (numeric scalar fields, (array field, its flattened names), unit per flattened field);
# a type's fields are fixed, so this is worked out from its first message.
_LAYOUTS: dict[str, tuple[tuple[str, ...], tuple[tuple[str, tuple[str, ...]], ...], dict[str, str]]] = {}


def _layout(msg):
    layout = _LAYOUTS.get(msg.get_type())
    if layout is None:
        by_name = getattr(msg, "fieldunits_by_name", None) or {}
        scalars, arrays, units = [], [], {}
        for name in msg.get_fieldnames():
            value = getattr(msg, name)
            if isinstance(value, (int, float)):
                scalars.append(name)
                units[name] = by_name.get(name, "")
            elif isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) for v in value):
                flat = tuple(f"{name}_{i}" for i in range(len(value)))
                arrays.append((name, flat))
                units.update(dict.fromkeys(flat, by_name.get(name, "")))
        layout = _LAYOUTS[msg.get_type()] = (tuple(scalars), tuple(arrays), units)
    return layout

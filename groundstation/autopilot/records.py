"""What MAVLink messages become: records in this project's units and frames (docs/conventions.md).

Every record names its sender (``system``, ``component``: MAVLink ids), the host time the bytes
arrived (``t_host_ns``; for a log, the time it stored) and, where the message carries one, the
autopilot's own time ``time_us`` (µs since boot) — the time base to use for rates and ``dt``
(a tlog's receive time can run 25x faster than the vehicle's, as in SITL autotests).
"""

from __future__ import annotations

from typing import NamedTuple


class ImuSample(NamedTuple):
    system: int
    component: int
    t_host_ns: int
    time_us: int
    source: str  # the message it came from: "RAW_IMU", "SCALED_IMU2", "HIGHRES_IMU", ...
    gyr_rad_s: tuple[float, float, float]  # body FRD
    acc_g: tuple[float, float, float]  # body FRD specific force (level at rest: (0, 0, -1))
    temperature_c: float  # NaN when not reported


class OnboardAttitude(NamedTuple):
    system: int
    component: int
    t_host_ns: int
    time_us: int
    source: str  # "ATTITUDE" or "ATTITUDE_QUATERNION"
    q: tuple[float, float, float, float]  # w, x, y, z; body -> NED


class MagReading(NamedTuple):
    system: int
    component: int
    t_host_ns: int
    time_us: int
    source: str
    mag_uT: tuple[float, float, float]  # body FRD


class BaroReading(NamedTuple):
    system: int
    component: int
    t_host_ns: int
    time_us: int
    source: str  # "SCALED_PRESSURE", "SCALED_PRESSURE2", "HIGHRES_IMU", ...
    pressure_hpa: float
    temperature_c: float  # NaN when not reported


class GpsReading(NamedTuple):
    system: int
    component: int
    t_host_ns: int
    time_us: int
    lat_deg: float
    lon_deg: float
    alt_m: float  # above mean sea level
    vel_n_m_s: float  # from ground speed and course; NaN when the receiver gives neither
    vel_e_m_s: float
    vel_d_m_s: float  # NaN: GPS_RAW_INT has no vertical speed
    fix_type: int  # MAVLink GPS_FIX_TYPE: 0-1 none, 2 2D, 3 3D, 4 DGPS, 5 RTK float, 6 RTK fixed
    satellites: int  # -1 when unknown


class LinkHealth(NamedTuple):
    """RADIO_STATUS (SiK radios): both ends' signal; rssi/noise in the radio's units (SiK: ~dBm*1.9+127)."""

    system: int
    component: int
    t_host_ns: int
    rssi: int  # local (ground) radio; 255 = unknown
    remote_rssi: int  # the aircraft's radio
    noise: int
    remote_noise: int
    rx_errors: int  # count, as the radio reports it
    fixed: int  # packets corrected by error correction
    tx_buffer_pct: int


class VehicleStatus(NamedTuple):
    """HEARTBEAT: what the sender is and what it is doing."""

    system: int
    component: int
    t_host_ns: int
    autopilot: int  # MAV_AUTOPILOT: 3 ArduPilot, 12 PX4, 8 none (a GCS, camera, companion)
    vehicle_type: int  # MAV_TYPE
    mode: str  # the custom mode's name (``modes.mavlink_mode``: "LOITER", "MANUAL", ...)
    armed: bool
    system_status: int  # MAV_STATE
    custom_mode: int  # the autopilot's own mode number (ArduPilot: per vehicle type; PX4: main and sub mode)


class Battery(NamedTuple):
    """SYS_STATUS: battery and the autopilot's own view of the link."""

    system: int
    component: int
    t_host_ns: int
    voltage_v: float  # NaN when unknown
    current_a: float  # NaN when unknown
    remaining_pct: float  # NaN when unknown
    drop_rate_comm_pct: float
    errors_comm: int


class GenericMessage(NamedTuple):
    """Any other message: its fields (arrays flattened to ``name_0``, ``name_1``, ...) and their units."""

    system: int
    component: int
    t_host_ns: int
    time_us: int | None
    msg_type: str
    fields: dict[str, float]
    units: dict[str, str]  # field -> unit, where pymavlink's message definition gives one


class StatusText(NamedTuple):
    """STATUSTEXT: one chunk of a text the autopilot says (MAVLink 2 splits a long one in 50-character
    chunks sharing an ``id``; ``id`` 0: the whole text in one message)."""

    system: int
    component: int
    t_host_ns: int
    severity: int  # MAV_SEVERITY: 0 emergency ... 7 debug
    text: str
    id: int
    chunk_seq: int


class ParamValue(NamedTuple):
    """PARAM_VALUE: one of the autopilot's parameters, its value as a number (``parameters.mavlink_value``)."""

    system: int
    component: int
    t_host_ns: int
    name: str
    value: float


Record = ImuSample | OnboardAttitude | MagReading | BaroReading | GpsReading | LinkHealth | VehicleStatus | Battery | GenericMessage | StatusText | ParamValue


# The tables a session keeps of these records, live (``session``'s MAVLink front-end) and logged
# (``tlog``): name, label, and per record attribute its column's field and unit.
RECORD_TABLES = {
    VehicleStatus: ("heartbeat", "HEARTBEAT: what the vehicle is and does",
                    {"autopilot": ("autopilot", ""), "vehicle_type": ("vehicle_type", ""), "armed": ("armed", ""),
                     "system_status": ("system_status", ""), "custom_mode": ("custom_mode", "")}),
    Battery: ("sys_status", "SYS_STATUS: battery and the autopilot's view of the link",
              {"voltage_v": ("voltage", "V"), "current_a": ("current", "A"), "remaining_pct": ("remaining", "%"),
               "drop_rate_comm_pct": ("drop_rate_comm", "%"), "errors_comm": ("errors_comm", "")}),
    LinkHealth: ("radio_status", "RADIO_STATUS: both radios' signal (SiK units)",
                 {"rssi": ("rssi", ""), "remote_rssi": ("remote_rssi", ""), "noise": ("noise", ""),
                  "remote_noise": ("remote_noise", ""), "rx_errors": ("rx_errors", ""), "fixed": ("fixed", ""),
                  "tx_buffer_pct": ("tx_buffer", "%")}),
}  # fmt: skip


def table_fields(record_type) -> tuple[str, str, list[str], dict[str, str]]:
    """The table of a mapped record type (``RECORD_TABLES``): its name, label, fields and their units."""
    name, label, columns = RECORD_TABLES[record_type]
    return name, label, [field for field, _ in columns.values()], {field: unit for field, unit in columns.values() if unit}

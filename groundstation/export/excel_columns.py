"""What the workbook's data sheets hold: columns with units in their headers, number formats and widths.

Angles come from ``attitude_columns``, so the workbook and the CSV export agree to the last digit.
"""

from __future__ import annotations

import math
from datetime import datetime, timezone

import numpy as np

from groundstation.export.columns import attitude_columns, select_rows
from groundstation.export.excel_stream import Block, Column
from groundstation.session.data import SessionData

SECONDS = "0.000"
TWO_PLACES = "0.00"
DATE_TIME = "yyyy-mm-dd hh:mm:ss.000"
COUNT = "0"
EXCEL_EPOCH = datetime(1899, 12, 30)  # day 0 of Excel's (1900) date system
CHART_POINTS = 2000  # per series: enough for the eye, few enough for Excel to stay responsive

SENSORS = (
    ("acc_x_g", "acc x (g)", "0.0000"), ("acc_y_g", "acc y (g)", "0.0000"), ("acc_z_g", "acc z (g)", "0.0000"),
    ("gyr_x_dps", "gyro x (°/s)", TWO_PLACES), ("gyr_y_dps", "gyro y (°/s)", TWO_PLACES),
    ("gyr_z_dps", "gyro z (°/s)", TWO_PLACES),
    ("temperature_c", "temperature (°C)", TWO_PLACES),
)  # fmt: skip
# The pipeline's tables of the other frames: (table, label, ((column, header, format), ...)).
AUX_SENSORS = (
    ("mag_raw", "mag", (("mag_x_uT", "mag x (µT, sensor axes)", TWO_PLACES),
                        ("mag_y_uT", "mag y (µT, sensor axes)", TWO_PLACES),
                        ("mag_z_uT", "mag z (µT, sensor axes)", TWO_PLACES),
                        ("heading_deg", "compass heading (°, tilt-compensated)", TWO_PLACES))),
    ("baro", "baro", (("pressure_Pa", "pressure (Pa)", "0.0"), ("temperature_degC", "baro temperature (°C)", TWO_PLACES))),
    ("gps", "GPS", (("lat_deg", "latitude (°)", "0.0000000"), ("lon_deg", "longitude (°)", "0.0000000"),
                    ("alt_m", "altitude (m)", "0.000"), ("vel_n_m_s", "velocity N (m/s)", TWO_PLACES),
                    ("vel_e_m_s", "velocity E (m/s)", TWO_PLACES), ("vel_d_m_s", "velocity D (m/s)", TWO_PLACES),
                    ("heading_deg", "heading (°)", TWO_PLACES), ("fix_type", "fix type (enum)", COUNT),
                    ("satellites", "satellites (count)", COUNT))),
    ("position", "fused position", (("pos_n_m", "fused north (m)", "0.000"), ("pos_e_m", "fused east (m)", "0.000"),
                                    ("pos_d_m", "fused down (m)", "0.000"), ("vel_n_m_s", "fused velocity N (m/s)", TWO_PLACES),
                                    ("vel_e_m_s", "fused velocity E (m/s)", TWO_PLACES),
                                    ("vel_d_m_s", "fused velocity D (m/s)", TWO_PLACES))),
)  # fmt: skip
STATUS = (
    ("battery_V", "battery (V)", "0.000"), ("retransmits", "retransmits (count)", COUNT),
    ("lost_acks", "lost acks (count)", COUNT), ("cpu_load_pct", "CPU load (%)", "0.0"), ("flags", "status flags (bits)", COUNT),
)  # fmt: skip
LINK = (
    ("frames", "frames (1/s)"), ("frames_lost", "frames lost (1/s)"), ("crc_errors", "CRC failures (1/s)"),
    ("bytes", "bytes (B/s)"), ("bytes_skipped", "bytes skipped (B/s)"),
)  # fmt: skip


def start_time(metadata: dict) -> datetime | None:
    """The recording's ``start_utc`` as a naive UTC datetime (Excel has no time zones), None when unknown."""
    try:
        start = datetime.fromisoformat(metadata.get("start_utc"))
    except (TypeError, ValueError):
        return None
    return start.astimezone(timezone.utc).replace(tzinfo=None) if start.tzinfo else start


def excel_days(moment: datetime) -> float:
    """An Excel date-time serial number: days since Excel's day 0."""
    return (moment - EXCEL_EPOCH).total_seconds() / 86400.0


def estimates(data: SessionData) -> dict:
    """The exported estimators and then the aircraft's own estimate, by column prefix."""
    out = dict(data.estimates)
    if data.onboard is not None:
        out["onboard"] = data.onboard
    return out


def attitude_block(data: SessionData, rows: np.ndarray) -> Block:
    time_s = data.time_s[rows]
    block = [Column("time (s)", time_s, SECONDS, 10)]
    start = start_time(data.metadata)
    if start is not None and data.pipeline is not None:  # from the link: start_utc is when its recording began
        block.append(Column("time (UTC)", excel_days(start) + time_s / 86400.0, DATE_TIME, 24))
    for name, q in estimates(data).items():
        angles = attitude_columns(name, q[rows])
        block += [Column(f"{name} {a} (°)", angles[f"{name}_{a}_deg"], TWO_PLACES, 14) for a in ("pitch", "roll", "yaw")]
    if "lam" in data.diagnostics.get("ahf", {}):
        block.append(Column("ahf λ (rad/s)", data.diagnostics["ahf"]["lam"][rows], "0.0000", 13))
    return block


def window_rows(time_s: np.ndarray, window: tuple[float, float], rate_hz: float | None) -> np.ndarray:
    """The rows of another table inside the exported time window, decimated like the IMU rows."""
    if not np.any((time_s >= window[0]) & (time_s <= window[1])):
        return np.zeros(0, dtype=int)
    return select_rows(time_s, window[0], window[1], rate_hz)


def table_block(table, label: str, spec, window, rate_hz) -> Block:
    """One of the pipeline's tables as a block with its own time column (its own rate)."""
    columns = table.to_dict()
    rows = window_rows(columns["time_s"], window, rate_hz)
    block = [Column(f"{label} time (s)", columns["time_s"][rows], SECONDS, 14)]
    return block + [Column(header, columns[name][rows], fmt, max(12, len(header) + 2)) for name, header, fmt in spec]


def sensor_blocks(data: SessionData, rows: np.ndarray, window, rate_hz) -> list[Block]:
    imu = [Column(header, data.sensors[name][rows], fmt, 14) for name, header, fmt in SENSORS if name in data.sensors]
    blocks = [[Column("time (s)", data.time_s[rows], SECONDS, 10), *imu]] if imu else []  # none: "estimated" mode
    if data.pipeline is not None:
        blocks += [table_block(data.pipeline.tables[t], label, spec, window, rate_hz) for t, label, spec in AUX_SENSORS
                   if len(data.pipeline.tables[t])]
    return blocks


def link_blocks(data: SessionData, window) -> list[Block]:
    """Per-second link counts (host clock, seconds from the first byte) and the aircraft's STATUS."""
    if data.pipeline is None:
        per_second = {"t_s": np.zeros(0), **{name: np.zeros(0) for name, _ in LINK}}
    else:
        per_second = data.pipeline.link.per_second.to_dict()
    seconds = (per_second["t_s"] + 1 > window[0]) & (per_second["t_s"] <= window[1])  # overlapping the window
    block = [Column("second from first byte (s)", per_second["t_s"][seconds].astype(np.int64), COUNT, 14)]
    block += [Column(header, per_second[name][seconds].astype(np.int64), COUNT, 16) for name, header in LINK]
    blocks = [block]
    if data.pipeline is not None and len(data.pipeline.tables["status"]):
        blocks.append(table_block(data.pipeline.tables["status"], "status", STATUS, window, None))
    return blocks


def chart_block(data: SessionData, rows: np.ndarray) -> Block:
    """Time, then every estimate's pitch, then every estimate's roll, at most CHART_POINTS rows."""
    rows = rows[:: max(1, math.ceil(len(rows) / CHART_POINTS))]
    block = [Column("time (s)", data.time_s[rows], "0.0", 10)]
    angles = {name: attitude_columns(name, q[rows]) for name, q in estimates(data).items()}
    for angle in ("pitch", "roll"):
        block += [Column(f"{name} {angle} (°)", a[f"{name}_{angle}_deg"], TWO_PLACES, 14) for name, a in angles.items()]
    return block

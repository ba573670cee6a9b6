"""What the workbook's data sheets hold: columns with units in their headers, number formats and widths.

Angles come from ``attitude_columns``, so the workbook and the CSV export agree to the last digit.
"""

from __future__ import annotations

import math
from datetime import datetime, timezone

import numpy as np

from groundstation.export.columns import attitude_columns, reading_tables, select_rows, sensor_columns
from groundstation.export.excel_stream import Block, Column
from groundstation.session_parts.catalogue import LINK_TABLES
from groundstation.session.product import SessionData

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


def attitude_block(data: SessionData, rows: np.ndarray) -> Block:
    time_s = data.time_s[rows]
    block = [Column("time (s)", time_s, SECONDS, 10)]
    start = start_time(data.metadata)
    if start is not None and data.link is not None:  # from the link: start_utc is when its recording began
        block.append(Column("time (UTC)", excel_days(start) + time_s / 86400.0, DATE_TIME, 24))
    for name, q in data.attitudes().items():
        angles = attitude_columns(name, q[rows])
        block += [Column(f"{name} {a} (°)", angles[f"{name}_{a}_deg"], TWO_PLACES, 14) for a in ("pitch", "roll", "yaw")]
    if "ahf" in data.estimated and "ahf_lam" in data.tables["imu"]:
        block.append(Column("ahf λ (rad/s)", data.tables["imu"]["ahf_lam"][rows], "0.0000", 13))
    return block


def window_rows(time_s: np.ndarray, window: tuple[float, float], rate_hz: float | None) -> np.ndarray:
    """The rows of another table inside the exported time window, decimated like the IMU rows."""
    if not np.any((time_s >= window[0]) & (time_s <= window[1])):
        return np.zeros(0, dtype=int)
    return select_rows(time_s, window[0], window[1], rate_hz)


def number_format(column) -> str:
    """An Excel number format showing the digits the column's resolution carries (catalogue.Column)."""
    return COUNT if column.decimals is None else ("0." + "0" * column.decimals if column.decimals else "0")


def table_block(data: SessionData, info, window, rate_hz) -> Block:
    """One of the session's tables (``catalogue.TableInfo``) as a block with its own time column (its own rate)."""
    columns = data.tables[info.name]
    rows = window_rows(columns["time_s"], window, rate_hz)
    label = info.export_prefix
    block = [Column(f"{label} time (s)", columns["time_s"][rows], SECONDS, 14)]
    for column in info.columns[1:]:
        header = f"{label} {column.header}" if not column.label.startswith(label) else column.header
        # as float64: a column held narrower (``catalogue.Column.held``, a log's float32) is written as the value it is
        block.append(Column(header, np.asarray(columns[column.name][rows], dtype=float), number_format(column), max(12, len(header) + 2)))
    return block


def sensor_blocks(data: SessionData, rows: np.ndarray, window, rate_hz) -> list[Block]:
    sensors = sensor_columns(data)
    imu = [Column(header, sensors[name][rows], fmt, 14) for name, header, fmt in SENSORS if name in sensors]
    blocks = [[Column("time (s)", data.time_s[rows], SECONDS, 10), *imu]] if imu else []  # none: "estimated" mode
    return blocks + [table_block(data, info, window, rate_hz) for info in reading_tables(data) if info.name not in LINK_TABLES]


def link_blocks(data: SessionData, window) -> list[Block]:
    """Per-second link counts (host clock, seconds from the first byte) and the aircraft's own link tables (STATUS)."""
    if data.link is None:
        per_second = {"t_s": np.zeros(0), **{name: np.zeros(0) for name, _ in LINK}}
    else:
        per_second = data.link.per_second
    seconds = (per_second["t_s"] + 1 > window[0]) & (per_second["t_s"] <= window[1])  # overlapping the window
    block = [Column("second from first byte (s)", per_second["t_s"][seconds].astype(np.int64), COUNT, 14)]
    block += [Column(header, per_second[name][seconds].astype(np.int64), COUNT, 16) for name, header in LINK]
    return [block] + [table_block(data, info, window, None) for info in reading_tables(data) if info.name in LINK_TABLES]


def chart_block(data: SessionData, rows: np.ndarray) -> Block:
    """Time, then every estimate's pitch, then every estimate's roll, at most CHART_POINTS rows."""
    rows = rows[:: max(1, math.ceil(len(rows) / CHART_POINTS))]
    block = [Column("time (s)", data.time_s[rows], "0.0", 10)]
    angles = {name: attitude_columns(name, q[rows]) for name, q in data.attitudes().items()}
    for angle in ("pitch", "roll"):
        block += [Column(f"{name} {angle} (°)", a[f"{name}_{angle}_deg"], TWO_PLACES, 14) for name, a in angles.items()]
    return block

"""A flight log (``.tlog``, DataFlash ``.bin``, PX4 ``.ulg``) as arrays on the autopilot's clock.

Each stream is a ``Series``: ``time_us`` (µs since the autopilot booted, strictly increasing) and
named columns whose names carry their units, in this project's frames (body FRD, body -> NED):

- ``imu``: ``gyr_{x,y,z}_rad_s``, ``acc_{x,y,z}_g`` — the one IMU the host estimators run on;
- ``onboard``: ``q{w,x,y,z}`` — the autopilot's own attitude estimate;
- ``mag``: ``mag_{x,y,z}_uT``; ``baro``: ``pressure_hpa``, ``temperature_c``;
- ``gps``: ``lat_deg``, ``lon_deg``, ``alt_m``, ``vel_{n,e,d}_m_s``, ``fix_type``, ``satellites``;
- ``truth``: ``q{w,x,y,z}`` — a simulator's true attitude when the log has one (PX4 SITL).

A stream the log lacks is None, and ``notes`` says so in words. ``events``: what the autopilot said
(texts, modes, arming, parameter changes: ``messages``) at its times; ``parameters``: name -> last value.
"""

from __future__ import annotations

import dataclasses
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from groundstation.session_parts.figures import rate_hz


Q_COLUMNS = ("qw", "qx", "qy", "qz")
IMU_COLUMNS = ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s", "acc_x_g", "acc_y_g", "acc_z_g")
MAG_COLUMNS = ("mag_x_uT", "mag_y_uT", "mag_z_uT")
GPS_COLUMNS = ("lat_deg", "lon_deg", "alt_m", "vel_n_m_s", "vel_e_m_s", "vel_d_m_s", "fix_type", "satellites")


@dataclasses.dataclass
class Series:
    time_us: np.ndarray  # (N,) int64, strictly increasing
    columns: dict[str, np.ndarray]  # name -> (N,) float
    source: str  # the message or topic it came from

    def __len__(self) -> int:
        return len(self.time_us)

    def stack(self, names) -> np.ndarray:
        return np.column_stack([self.columns[n] for n in names])

    @property
    def rate_hz(self) -> float:
        """Median rate on the autopilot's clock (``figures.rate_hz``); NaN with fewer than two samples."""
        return rate_hz(self.time_us / 1e6)


def series(time_us, columns: dict, source: str) -> Series | None:
    """Sorted by time, with repeated or backward times dropped (a tlog can hold a message twice); None if empty."""
    time_us = np.asarray(time_us, dtype=np.int64)
    if len(time_us) == 0:
        return None
    order = np.argsort(time_us, kind="stable")
    time_us = time_us[order]
    keep = np.concatenate([[True], np.diff(time_us) > 0])
    return Series(time_us[keep], {n: np.asarray(v, dtype=float)[order][keep] for n, v in columns.items()}, source)


GPS_EPOCH_UNIX_S = 315_964_800  # 1980-01-06T00:00:00Z, GPS week 0
GPS_MINUS_UTC_S = 18  # leap seconds GPS time runs ahead of UTC (since 2017-01-01; none announced since)


def gps_unix_us(week, ms_of_week):
    """GPS week and milliseconds of the week as UTC µs since 1970."""
    return (GPS_EPOCH_UNIX_S - GPS_MINUS_UTC_S + np.asarray(week, dtype=np.int64) * 604_800) * 1_000_000 \
        + np.asarray(ms_of_week, dtype=np.int64) * 1000


def utc_offset_us(utc_us, boot_us) -> int | None:
    """UTC minus the boot clock from the rows that carry both (a GPS's time of fix and the time it was
    logged): their median, which a late row cannot move; None without rows."""
    differences = np.asarray(utc_us, dtype=np.int64) - np.asarray(boot_us, dtype=np.int64)
    return int(np.median(differences)) if len(differences) else None


def utc_text(unix_us: int) -> str:
    """UTC µs since 1970 as ISO 8601 (``2023-07-06T09:12:18.265127Z``), as a recording's ``start_utc``."""
    moment = datetime.fromtimestamp(unix_us // 1_000_000, timezone.utc).replace(microsecond=unix_us % 1_000_000)
    return moment.isoformat(timespec="microseconds").replace("+00:00", "Z")


PLAUSIBLE_MARGIN_US = 60_000_000


def implausible_times(time_us) -> np.ndarray:
    """Rows whose timestamps lie far outside the stream's span: damaged bytes (one flipped bit in a
    timestamp's top byte puts a row at 7.2e10 s). The span is that of the 1st to 99th percentile of the
    times, which a few damaged rows cannot move; a time more than the span and a minute beyond it is
    implausible (a logging pause of that length would be one too)."""
    time_us = np.asarray(time_us, dtype=np.float64)
    if len(time_us) == 0 or time_us.max() - time_us.min() <= PLAUSIBLE_MARGIN_US:
        return np.zeros(len(time_us), dtype=bool)  # within a minute of each other: none beyond the reach below
    lo, hi = np.percentile(time_us, [1.0, 99.0])
    reach = (hi - lo) + PLAUSIBLE_MARGIN_US
    return (time_us < lo - reach) | (time_us > hi + reach)


def implausible_message(source: str, time_us: np.ndarray) -> str:
    seconds = np.asarray(time_us, dtype=np.float64) / 1e6
    rows = "1 row" if len(seconds) == 1 else f"{len(seconds)} rows"
    return (f"{source}: {rows} at implausible times ({', '.join(f'{s:.3g} s' for s in seconds[:3])}"
            f"{', ...' if len(seconds) > 3 else ''}; far beyond the log's span) dropped: damaged bytes")


def cut_message(unfinished_bytes: int) -> str:
    """What a log that ends inside a record lost, said the same for every format. (A DataFlash log copied
    in whole blocks ends mid-record too, and is told apart by its size: ``dataflash.BLOCK_BYTES``.)"""
    return (f"the file ends inside a record ({unfinished_bytes} bytes of an unfinished one): the log was cut short "
            "or stopped mid-write, and anything after it is missing")


@dataclasses.dataclass
class FlightLog:
    path: Path
    format: str  # its name in ``formats.FORMATS``: "tlog", "dataflash", "ulog"
    autopilot: str  # "ArduPilot", "PX4", or what the log says
    imu: Series | None = None
    onboard: Series | None = None
    mag: Series | None = None
    baro: Series | None = None
    gps: Series | None = None
    truth: Series | None = None
    tables: dict[str, Series] = dataclasses.field(default_factory=dict)  # other messages, per type
    units: dict[str, dict[str, str]] = dataclasses.field(default_factory=dict)  # table -> column -> unit
    notes: list[str] = dataclasses.field(default_factory=list)
    damage: list[str] = dataclasses.field(default_factory=list)  # what the reader dropped as damaged
    warnings: list[str] = dataclasses.field(default_factory=list)  # what a flyer must hear of the reading (names kept apart)
    events: list[tuple[int, dict]] = dataclasses.field(default_factory=list)  # (time µs, event without times)
    parameters: dict[str, float] = dataclasses.field(default_factory=dict)
    parameter_defaults: dict[str, float] = dataclasses.field(default_factory=dict)  # name -> default, where the log says it
    utc_offset_us: int | None = None  # UTC (µs since 1970) minus the boot clock, from the log's GPS or UTC time
    utc_source: str = ""  # where utc_offset_us comes from, in words
    imu_choice: str = ""  # which IMU stream is ``imu`` and why (``imu_choice``)

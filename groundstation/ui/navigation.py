"""The plotted quantities of the aiding sensors (compass, barometer, GPS, a fused position) and the
newest heading with its source; no Qt.

Headings are wrapped to 0..360° as a compass reads them. The GPS track is north/east metres from the
first fix (flat earth: fine for flights of a few km); heights are relative to the first reading, the
barometer's from pressure by the ISA formula (``geodesy.pressure_altitude_m``) with the first reading's
pressure and temperature as the ground. A fused position table (``view.tables["position"]``,
NED metres) is plotted when the session has one.
"""

from __future__ import annotations

import math

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from firmware_protocol import SPEC
from groundstation.geodesy import ned_from_geodetic, pressure_altitude_m
from groundstation.session.view import ProductView
from groundstation.session_parts.table import Table
from groundstation.ui.series import Series

FIX_2D = SPEC.enums["gps_fix"].values["fix_2d"]
FIX_NAMES = {value: "no fix" if name == "none" else name.removeprefix("fix_").upper()
             for name, value in SPEC.enums["gps_fix"].values.items()}
# An autopilot's GPS_RAW_INT.fix_type is MAVLink's GPS_FIX_TYPE: its own words, before the comma
# ("RTK Fixed, 3D position" -> "RTK Fixed").
MAVLINK_FIX_NAMES = {value: entry.description.split(",")[0].rstrip(".") for value, entry in mavlink.enums["GPS_FIX_TYPE"].items()
                     if not entry.name.endswith("ENUM_END")}


def fix_name(fix_type: float, protocol: str | None) -> str:
    """A GPS solution's fix type in words, by the numbering of the link that carried it."""
    names = MAVLINK_FIX_NAMES if protocol == "mavlink" else FIX_NAMES
    return names.get(int(fix_type), f"fix type {int(fix_type)}") if math.isfinite(fix_type) else "—"
HEADING_STALE_S = 2.0  # a heading reading this much older than the newest sample no longer counts


def columns_of(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    return {name: rows[:, i] for i, name in enumerate(columns)}


def valid_heading_deg(heading_deg: np.ndarray) -> np.ndarray:
    """0..360° (360 becomes 0); NaN where the receiver has none (0xFFFF reads 655.35)."""
    heading_deg = np.asarray(heading_deg, dtype=float)
    return np.where((heading_deg >= 0.0) & (heading_deg <= 360.0), np.mod(heading_deg, 360.0), np.nan)


def compass_quantities(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The session's tilt-compensated compass heading, 0..360°, and the field in sensor axes (µT)."""
    col = columns_of(rows, columns)
    return {"compass_heading_deg": np.mod(col["heading_deg"], 360.0), **{f"mag_{a}_uT": col[f"mag_{a}_uT"] for a in "xyz"}}


def fused_quantities(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    col = columns_of(rows, columns)
    return {"fused_north_m": col["pos_n_m"], "fused_east_m": col["pos_e_m"], "fused_height_m": -col["pos_d_m"]}


class BaroQuantities:
    """Barometric height above the first reading; pressure (hPa) and temperature as read."""

    def __init__(self):
        self.ground: tuple[float, float] | None = None  # pressure (Pa) and temperature (°C) of the first reading

    def __call__(self, rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        col = columns_of(rows, columns)
        if self.ground is None:
            self.ground = float(col["pressure_Pa"][0]), float(col["temperature_degC"][0])
        return {"baro_height_m": pressure_altitude_m(col["pressure_Pa"], *self.ground),
                "baro_pressure_hPa": col["pressure_Pa"] / 100.0, "baro_temperature_degC": col["temperature_degC"]}


class GpsQuantities:
    """Track (north/east metres from the first fix), height above the first fix, ground speed,
    heading; NaN on solutions without a fix."""

    def __init__(self):
        self.origin: tuple[float, float, float] | None = None  # latitude (°), longitude (°), altitude (m)

    def __call__(self, rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        col = columns_of(rows, columns)
        fixed = col["fix_type"] >= FIX_2D
        if self.origin is None and fixed.any():
            first = int(np.argmax(fixed))
            self.origin = tuple(float(col[name][first]) for name in ("lat_deg", "lon_deg", "alt_m"))
        unfixed = np.where(fixed, 0.0, np.nan)  # NaN where there is no fix
        ned = ned_from_geodetic(col["lat_deg"], col["lon_deg"], col["alt_m"], self.origin or (math.nan,) * 3)
        return {
            "gps_north_m": ned[:, 0] + unfixed,
            "gps_east_m": ned[:, 1] + unfixed,
            "gps_height_m": -ned[:, 2] + unfixed,
            "gps_speed_m_s": np.hypot(col["vel_n_m_s"], col["vel_e_m_s"]) + unfixed,
            "gps_heading_deg": valid_heading_deg(col["heading_deg"]) + unfixed,
        }


def aiding_series(tables: dict[str, Table]) -> dict[str, Series]:
    """A ``Series`` for each aiding table the session has: "mag", "baro", "gps", "position"."""
    derive = {"mag_raw": ("mag", compass_quantities), "baro": ("baro", BaroQuantities()),
              "gps": ("gps", GpsQuantities()), "position": ("position", fused_quantities)}
    return {name: Series(tables[table], quantities) for table, (name, quantities) in derive.items()
            if tables.get(table) is not None}


def newest_row(table: Table | None) -> dict[str, float] | None:
    if table is None:
        return None
    last = table.tail(1)
    return dict(zip(table.columns, last[0].tolist())) if len(last) else None


def heading_now(view: ProductView) -> tuple[float, str] | None:
    """The newest heading (0..360°) and its source: the GPS when its newest solution has a fix and
    a heading, else the compass; None when neither has a reading within ``HEADING_STALE_S`` of the
    newest sample."""
    gps, mag, imu = newest_row(view.tables.get("gps")), newest_row(view.tables.get("mag_raw")), newest_row(view.imu)
    now_s = max(row["time_s"] for row in (gps, mag, imu) if row is not None) if gps or mag or imu else math.nan
    candidates = []
    if gps is not None and gps["fix_type"] >= FIX_2D:
        candidates.append((gps, float(valid_heading_deg(gps["heading_deg"])), "GPS"))
    if mag is not None:
        candidates.append((mag, mag["heading_deg"] % 360.0, "compass"))
    for row, heading_deg, source in candidates:
        if math.isfinite(heading_deg) and now_s - row["time_s"] <= HEADING_STALE_S:
            return heading_deg, source
    return None

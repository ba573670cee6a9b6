"""Heights and local positions: pressure altitude (ISA troposphere) and a flat-earth NED frame
around a reference point, good to centimetres over the few kilometres a small quadrotor flies.
"""

from __future__ import annotations

import math

import numpy as np

EARTH_RADIUS_M = 6_371_000.0  # mean radius; the flat-earth scale error over 5 km is < 1 mm/m
ISA_LAPSE_K_PER_M = 0.0065
ISA_EXPONENT = 5.25588  # g M / (R L)


def pressure_pa(altitude_m, ground_pressure_pa: float, ground_temperature_c: float = 15.0):
    """ISA troposphere: ``p = p0 (1 - L h / T0)^(g M / (R L))`` at ``altitude_m`` above the ground reference."""
    t0_k = ground_temperature_c + 273.15
    return ground_pressure_pa * (1.0 - ISA_LAPSE_K_PER_M * np.asarray(altitude_m, dtype=float) / t0_k) ** ISA_EXPONENT


def pressure_altitude_m(pressure_pa, ground_pressure_pa: float, ground_temperature_c: float = 15.0):
    """Height (m) above the point where the pressure is ``ground_pressure_pa``: ``pressure_pa`` inverted."""
    t0_k = ground_temperature_c + 273.15
    ratio = np.asarray(pressure_pa, dtype=float) / ground_pressure_pa
    # libm's pow on each value (Python's float ``**``), not NumPy's, whose AVX-512 vector code differs in the
    # last bit on some inputs: one reading at a time (live) and a file's all at once give the same heights
    exponent = 1.0 / ISA_EXPONENT
    powered = [r**exponent if r >= 0.0 else math.nan for r in ratio.ravel().tolist()]
    return t0_k / ISA_LAPSE_K_PER_M * (1.0 - np.array(powered).reshape(ratio.shape))


def ned_from_geodetic(lat_deg, lon_deg, alt_m, origin: tuple[float, float, float]) -> np.ndarray:
    """(…, 3) north, east, down (m) of points relative to ``origin`` = (lat °, lon °, alt m)."""
    lat0, lon0, alt0 = origin
    north = np.radians(np.asarray(lat_deg, dtype=float) - lat0) * EARTH_RADIUS_M
    east = np.radians(np.asarray(lon_deg, dtype=float) - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return np.stack(np.broadcast_arrays(north, east, alt0 - np.asarray(alt_m, dtype=float)), axis=-1)


def geodetic_from_ned(pos_ned_m, origin: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude (°), longitude (°) and altitude (m) of NED positions (…, 3): ``ned_from_geodetic`` inverted."""
    lat0, lon0, alt0 = origin
    pos = np.asarray(pos_ned_m, dtype=float)
    lat = lat0 + np.degrees(pos[..., 0] / EARTH_RADIUS_M)
    lon = lon0 + np.degrees(pos[..., 1] / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
    return lat, lon, alt0 - pos[..., 2]

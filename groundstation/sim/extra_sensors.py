"""Optional magnetometer, barometer and GPS models (off by default: the paper's craft has none).

Each takes the truth of a block of samples and returns physical values with noise; the firmware
packs them into ``MAG_RAW``, ``BARO`` and ``GPS`` frames at their own rates.

- Magnetometer: the earth field (NED, µT) on the sensor axes, plus a hard-iron offset fixed per
  part and white noise. Its axes are taken to be the MPU-6050's.
- Barometer: ISA troposphere pressure at the truth altitude above the take-off point, plus noise.
- GPS: position around a reference point (flat earth, fine for flights of a few km), NED velocity,
  heading as a dual-antenna receiver gives it, each with white noise.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from groundstation import geodesy
from groundstation import mounting as mountings
from groundstation import quaternion as quat
from groundstation.sim.profiles import Truth

@dataclasses.dataclass(frozen=True)
class AuxSettings:
    mag_field_ned_ut: tuple[float, float, float] = (20.0, 0.0, 45.0)  # a mid-latitude field, no declination
    mag_noise_ut: float = 0.3  # σ per sample
    mag_hard_iron_tolerance_ut: float = 10.0  # per-axis offset drawn with σ = tolerance/3
    baro_noise_pa: float = 2.0  # σ per sample (≈ 0.17 m)
    ground_pressure_pa: float = 101_325.0
    ground_temperature_c: float = 15.0
    origin_lat_deg: float = 52.5
    origin_lon_deg: float = 13.4
    origin_alt_m: float = 40.0
    gps_position_noise_m: float = 1.0  # σ per axis
    gps_velocity_noise_m_s: float = 0.05  # σ per axis
    gps_heading_noise_deg: float = 0.5  # σ
    gps_satellites: int = 10


def magnetometer_ut(truth: Truth, settings: AuxSettings, mounting: int, hard_iron_ut: np.ndarray, rng) -> np.ndarray:
    """Field on the sensor axes (n, 3), µT."""
    field_body = quat.rotate(quat.conjugate(truth.q_body_to_ned), np.array(settings.mag_field_ned_ut))
    noise = rng.normal(0.0, settings.mag_noise_ut, field_body.shape)
    return mountings.body_to_sensor(field_body, mounting) + hard_iron_ut + noise


def barometer(truth: Truth, settings: AuxSettings, rng) -> tuple[np.ndarray, np.ndarray]:
    """Pressure (n,) in Pa and temperature (n,) in °C."""
    altitude_m = -truth.pos_ned_m[:, 2]
    pressure = geodesy.pressure_pa(altitude_m, settings.ground_pressure_pa, settings.ground_temperature_c) + rng.normal(0.0, settings.baro_noise_pa, len(altitude_m))
    return pressure, settings.ground_temperature_c - 0.0065 * altitude_m


def gps(truth: Truth, settings: AuxSettings, rng) -> dict[str, np.ndarray]:
    """Latitude/longitude (deg), altitude (m), NED velocity (m/s), heading (deg, 0..360); each (n,)."""
    n = len(truth.t_s)
    pos = truth.pos_ned_m + rng.normal(0.0, settings.gps_position_noise_m, (n, 3))
    vel = truth.vel_ned_m_s + rng.normal(0.0, settings.gps_velocity_noise_m_s, (n, 3))
    yaw_deg = np.degrees(quat.to_euler_zyx(truth.q_body_to_ned)[:, 0]) + rng.normal(0.0, settings.gps_heading_noise_deg, n)
    lat, lon, alt = geodesy.geodetic_from_ned(pos, origin(settings))
    return {
        "lat": lat,
        "lon": lon,
        "alt": alt,
        "vel_n": vel[:, 0],
        "vel_e": vel[:, 1],
        "vel_d": vel[:, 2],
        "heading": np.mod(yaw_deg, 360.0),
    }


def origin(settings: AuxSettings) -> tuple[float, float, float]:
    """The GPS reference point (lat °, lon °, alt m): the simulated craft's take-off point."""
    return (settings.origin_lat_deg, settings.origin_lon_deg, settings.origin_alt_m)

"""A simulated flight as arrays in physical units on the body axes, for experiments and tests.

The same sensor models as the streaming simulator (``imu``, ``extra_sensors``), without the
firmware, the link or the bytes: the quickest way to put an estimator against truth. The IMU goes
through its int16 registers (quantisation and saturation at the chosen full scale) and back; its
offset registers hold the turn-on biases, as after the firmware's calibration at rest (the warm-up
drift and bias random walk remain). Aiding sensors report at their own rates; the samples between
readings are NaN rows, the convention of ``Estimator.run`` (``estimation.base``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from groundstation import geodesy
from groundstation import mounting as mountings
from groundstation import units
from groundstation.estimation.tilt import wrap_pi
from groundstation.sim import extra_sensors
from groundstation.sim.imu import MPU6050, MPU6050Settings
from groundstation.sim.profiles import Profile, Truth, make_profile
from groundstation.sim.seeds import stream


@dataclasses.dataclass
class SimRun:
    """``n`` samples at ``1 / dt_s`` Hz; aiding arrays are NaN on samples without a new reading."""

    truth: Truth
    dt_s: float
    gyr_rad_s: np.ndarray  # (n, 3) body axes
    acc_g: np.ndarray  # (n, 3) body axes, specific force in standard gravities
    temperature_c: np.ndarray  # (n,)
    mag_ut: np.ndarray  # (n, 3) body axes, µT (hard iron included)
    baro_alt_m: np.ndarray  # (n,) altitude above the start from the ISA pressure
    gps: np.ndarray  # (n, 4) vel_n, vel_e, vel_d (m/s), heading (rad): ``GpsFix`` rows
    gps_pos_ned_m: np.ndarray  # (n, 3) GPS position relative to the origin, NED
    hard_iron_ut: np.ndarray  # (3,) the magnetometer's offset, body axes

    def __len__(self) -> int:
        return len(self.truth.t_s)


def simulate(
    profile: Profile | str,
    duration_s: float | None = None,
    seed: int = 0,
    rate_hz: float = 100.0,
    accel_fs_g: int = 8,
    gyro_fs_dps: int = 2000,
    mag_rate_hz: float = 0.0,
    baro_rate_hz: float = 0.0,
    gps_rate_hz: float = 0.0,
    imu: MPU6050Settings | None = None,
    aux: extra_sensors.AuxSettings | None = None,
    gyro_bias_left_dps: float = 0.0,
) -> SimRun:
    """Sample ``profile`` (a ``Profile`` or a name for ``make_profile``) with every sensor asked for.

    ``gyro_bias_left_dps``: the turn-on bias the calibration missed on every sensor axis (a board that
    kept an old calibration, or calibrated while moving), which the estimators must find themselves."""
    if isinstance(profile, str):
        profile = make_profile(profile, duration_s, seed)
    aux = aux or extra_sensors.AuxSettings()
    n = int(round(profile.duration_s * rate_hz))
    truth = profile.truth(np.arange(n) / rate_hz)
    part = MPU6050(imu or MPU6050Settings(), accel_fs_g, gyro_fs_dps, mountings.DEFAULT_MOUNTING, rate_hz, seed)
    part.gyro_offset_dps = part.gyro_turn_on_bias_dps - gyro_bias_left_dps
    part.accel_offset_g = part.accel_turn_on_bias_g.copy()
    registers = part.sample(truth)
    to_body = mountings.matrix(mountings.DEFAULT_MOUNTING)
    gyr = units.gyro_counts_to_rad_s(registers.gyr_counts, gyro_fs_dps) @ to_body.T
    acc = units.accel_counts_to_g(registers.acc_counts, accel_fs_g) @ to_body.T

    hard_iron_sensor = stream(seed, "mag_part").normal(0.0, aux.mag_hard_iron_tolerance_ut / 3.0, 3)
    mag = extra_sensors.magnetometer_ut(truth, aux, mountings.DEFAULT_MOUNTING, hard_iron_sensor, stream(seed, "mag"))
    pressure, _ = extra_sensors.barometer(truth, aux, stream(seed, "baro"))
    fix = extra_sensors.gps(truth, aux, stream(seed, "gps"))
    gps_pos = geodesy.ned_from_geodetic(fix["lat"], fix["lon"], fix["alt"], extra_sensors.origin(aux))
    gps = np.column_stack([fix["vel_n"], fix["vel_e"], fix["vel_d"], wrap_pi(np.radians(fix["heading"]))])
    return SimRun(
        truth=truth,
        dt_s=1.0 / rate_hz,
        gyr_rad_s=gyr,
        acc_g=acc,
        temperature_c=registers.temperature_c,
        mag_ut=_every(mountings.sensor_to_body(mag, mountings.DEFAULT_MOUNTING), rate_hz, mag_rate_hz),
        baro_alt_m=_every(geodesy.pressure_altitude_m(pressure, aux.ground_pressure_pa, aux.ground_temperature_c), rate_hz, baro_rate_hz),
        gps=_every(gps, rate_hz, gps_rate_hz),
        gps_pos_ned_m=_every(gps_pos, rate_hz, gps_rate_hz),
        hard_iron_ut=mountings.sensor_to_body(hard_iron_sensor, mountings.DEFAULT_MOUNTING),
    )


def _every(values: np.ndarray, rate_hz: float, sensor_rate_hz: float) -> np.ndarray:
    """Keep one reading every ``rate_hz / sensor_rate_hz`` samples (the first sample has one); NaN elsewhere."""
    out = np.full(np.shape(values), np.nan)
    if sensor_rate_hz > 0:
        step = max(1, int(round(rate_hz / sensor_rate_hz)))
        out[::step] = values[::step]
    return out

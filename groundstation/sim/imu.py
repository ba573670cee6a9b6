"""MPU-6050 sensor model: truth in, int16 register counts out.

For each sample, on the sensor's own axes (the mounting maps body to sensor axes)::

    gyro_dps  = (I + E_g) ω_dps + b_g(t) + n_g        counts = round((gyro_dps - offset) · LSB/(°/s))
    accel_g   = (I + E_a) f_g   + b_a(t) + n_a        counts = round((accel_g - offset) · LSB/g)

``E`` holds the scale errors (diagonal) and cross-axis sensitivity (off-diagonal), fixed per part;
``b(t)`` is the turn-on bias + a temperature coefficient × the warm-up + a random walk; ``n`` is white
noise whose one-sided density is the datasheet's (σ = density · √(rate/2), i.e. the datasheet's
"total RMS = density · √bandwidth" with the bandwidth at Nyquist). Counts saturate at the int16 limits
as the part does. ``offset`` models the chip's offset registers (XG_OFFS_USR…, XA_OFFS…), which the
firmware writes after calibrating: the registers then read bias-corrected values.

Per-part errors are drawn once per seed: the datasheet gives production tolerances (±x), which are
read here as 3σ limits of a normal distribution. The defaults are the MPU-6000/6050 Product
Specification rev 3.4 values (tables 6.1, 6.2) where it gives one; the bias random walks and the
warm-up curve are not in the datasheet and are typical values for this class of part, said so below.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from groundstation import mounting as mountings
from groundstation import units
from groundstation.sim.profiles import Truth
from groundstation.sim.seeds import stream
from groundstation.sim.vibration import MotorVibration, VibrationSettings


@dataclasses.dataclass(frozen=True)
class MPU6050Settings:
    """Error model of one MPU-6050; every field's unit is in its name. Defaults: the datasheet."""

    gyro_noise_dps_rthz: float = 0.005  # rate noise spectral density (table 6.1)
    accel_noise_ug_rthz: float = 400.0  # power spectral density (table 6.2)
    gyro_bias_tolerance_dps: float = 20.0  # initial ZRO tolerance ±20 °/s (3σ)
    accel_bias_tolerance_mg: tuple[float, float, float] = (50.0, 50.0, 80.0)  # zero-G initial tolerance, x y z (3σ)
    gyro_scale_tolerance: float = 0.03  # sensitivity scale factor tolerance ±3 % (3σ)
    accel_scale_tolerance: float = 0.03  # initial calibration tolerance ±3 % (3σ)
    cross_axis_tolerance: float = 0.02  # cross-axis sensitivity ±2 % (3σ), both sensors
    # ZRO variation over temperature: ±20 °/s over -40..85 °C; zero-G level change ±35 mg (x, y) and
    # ±60 mg (z) over 0..70 °C; as per-°C 3σ coefficients.
    gyro_bias_tempco_dps_per_c: float = 20.0 / 125.0
    accel_bias_tempco_mg_per_c: tuple[float, float, float] = (35.0 / 70.0, 35.0 / 70.0, 60.0 / 70.0)
    # Not in the datasheet: bias random walks typical of consumer MEMS of this class.
    gyro_bias_walk_dps_rts: float = 0.001  # °/s per √s
    accel_bias_walk_ug_rts: float = 10.0  # µg per √s
    # Not in the datasheet: die temperature from power-up, T = end + (start - end) e^(-t/τ).
    temperature_start_c: float = 25.0
    temperature_end_c: float = 30.0
    warmup_time_constant_s: float = 120.0
    # Not the part's: the motors' vibration reaching it (sim/vibration.py); off by default.
    vibration: VibrationSettings = VibrationSettings()


@dataclasses.dataclass(frozen=True)
class ImuSamples:
    """``n`` samples: int16 counts (n, 3) on the sensor axes, die temperature (n,) in °C."""

    acc_counts: np.ndarray
    gyr_counts: np.ndarray
    temperature_c: np.ndarray


def _part_matrix(rng, scale_tolerance: float, cross_tolerance: float) -> np.ndarray:
    """I + E: per-axis scale errors on the diagonal, cross-axis coupling off it (3σ tolerances)."""
    e = rng.normal(0.0, cross_tolerance / 3.0, (3, 3))
    np.fill_diagonal(e, rng.normal(0.0, scale_tolerance / 3.0, 3))
    return np.eye(3) + e


class MPU6050:
    """One simulated part, sampled at ``rate_hz``; call ``sample`` on consecutive blocks of truth."""

    def __init__(self, settings: MPU6050Settings, accel_fs_g: int, gyro_fs_dps: int, mounting: int, rate_hz: float, seed: int):
        self.settings = s = settings
        self.accel_fs_g, self.gyro_fs_dps = accel_fs_g, gyro_fs_dps
        self._body_to_sensor = mountings.matrix(mounting).T
        self._dt_s = 1.0 / rate_hz
        part = stream(seed, "imu_part")
        self._gyr_matrix = _part_matrix(part, s.gyro_scale_tolerance, s.cross_axis_tolerance)
        self._acc_matrix = _part_matrix(part, s.accel_scale_tolerance, s.cross_axis_tolerance)
        self.gyro_turn_on_bias_dps = part.normal(0.0, s.gyro_bias_tolerance_dps / 3.0, 3)
        self.accel_turn_on_bias_g = part.normal(0.0, 1.0, 3) * np.array(s.accel_bias_tolerance_mg) / 3000.0
        self._gyr_tempco_dps_per_c = part.normal(0.0, s.gyro_bias_tempco_dps_per_c / 3.0, 3)
        self._acc_tempco_g_per_c = part.normal(0.0, 1.0, 3) * np.array(s.accel_bias_tempco_mg_per_c) / 3000.0
        self._gyr_noise, self._acc_noise = stream(seed, "gyro_noise"), stream(seed, "accel_noise")
        self._gyr_walk_rng, self._acc_walk_rng = stream(seed, "gyro_walk"), stream(seed, "accel_walk")
        self._gyr_walk_dps = np.zeros(3)
        self._acc_walk_g = np.zeros(3)
        sqrt_half_rate = math.sqrt(rate_hz / 2.0)
        self._gyr_sigma_dps = s.gyro_noise_dps_rthz * sqrt_half_rate
        self._acc_sigma_g = s.accel_noise_ug_rthz * 1e-6 * sqrt_half_rate
        # The offset registers (written by the firmware), in physical units.
        self.gyro_offset_dps = np.zeros(3)
        self.accel_offset_g = np.zeros(3)
        self._vibration = MotorVibration(s.vibration) if s.vibration.hover_hz > 0 else None

    def temperature_c(self, t_s) -> np.ndarray:
        s = self.settings
        return s.temperature_end_c + (s.temperature_start_c - s.temperature_end_c) * np.exp(-np.asarray(t_s) / s.warmup_time_constant_s)

    def _walk(self, rng, state: np.ndarray, sigma_per_rts: float, n: int) -> np.ndarray:
        """Random walk over the next ``n`` samples, continuing from ``state`` (updated in place)."""
        path = state + np.cumsum(rng.normal(0.0, sigma_per_rts * math.sqrt(self._dt_s), (n, 3)), axis=0)
        state[:] = path[-1]
        return path

    def analog(self, truth: Truth) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Gyro (°/s) and accelerometer (g) readings (n, 3) before conversion, and the temperature (n,)."""
        n = len(truth.t_s)
        s = self.settings
        temp_c = self.temperature_c(truth.t_s)
        warm_c = (temp_c - s.temperature_start_c)[:, None]
        rate_dps = np.degrees(truth.rate_body_rad_s @ self._body_to_sensor.T)
        force_body_m_s2 = truth.specific_force_body_m_s2()
        if self._vibration is not None:  # body axes, then to the sensor's with the motion
            shake_dps, shake_m_s2 = self._vibration(truth.t_s, force_body_m_s2)
            rate_dps = rate_dps + shake_dps @ self._body_to_sensor.T
            force_body_m_s2 = force_body_m_s2 + shake_m_s2
        force_g = (force_body_m_s2 @ self._body_to_sensor.T) / units.STANDARD_GRAVITY_M_S2
        gyr_dps = (
            rate_dps @ self._gyr_matrix.T
            + self.gyro_turn_on_bias_dps
            + warm_c * self._gyr_tempco_dps_per_c
            + self._walk(self._gyr_walk_rng, self._gyr_walk_dps, s.gyro_bias_walk_dps_rts, n)
            + self._gyr_noise.normal(0.0, self._gyr_sigma_dps, (n, 3))
        )
        acc_g = (
            force_g @ self._acc_matrix.T
            + self.accel_turn_on_bias_g
            + warm_c * self._acc_tempco_g_per_c
            + self._walk(self._acc_walk_rng, self._acc_walk_g, s.accel_bias_walk_ug_rts * 1e-6, n)
            + self._acc_noise.normal(0.0, self._acc_sigma_g, (n, 3))
        )
        return gyr_dps, acc_g, temp_c

    def sample(self, truth: Truth) -> ImuSamples:
        """The registers for the truth at consecutive sample instants (one call per block, in order)."""
        return self.registers(*self.analog(truth))

    def registers(self, gyr_dps: np.ndarray, acc_g: np.ndarray, temperature_c: np.ndarray) -> ImuSamples:
        """Analog readings to counts with the current offset registers."""
        # units' conversions round to the nearest count and saturate at the int16 limits, as the ADC does.
        return ImuSamples(
            acc_counts=units.accel_g_to_counts(acc_g - self.accel_offset_g, self.accel_fs_g),
            gyr_counts=units.gyro_dps_to_counts(gyr_dps - self.gyro_offset_dps, self.gyro_fs_dps),
            temperature_c=temperature_c,
        )

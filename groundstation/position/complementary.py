"""Seed 004's position estimators: the accelerometer channel corrected by barometer and GPS.

Per NED axis (section 2 of the paper; equations of the loops in ``design``):

1. prediction, every sample: ``a = acc_ned - b̂``; ``p += v dt + a dt²/2``; ``v += a dt``
   (the accelerometer channel: NED linear acceleration integrated twice);
2. correction, on a sample with a reading: ``e = z - p``, then ``p += kp e Δ``, ``v += kv e Δ`` and,
   dual channel only, ``b̂ -= ki e Δ``, where ``Δ`` is the time since that axis's previous reading
   (the continuous loops of ``design`` held over the reading interval);
3. dual channel with GPS velocity ``u``: ``e_v = u - v``, ``v += kv e_v Δ``, ``b̂ -= ki e_v Δ``.

Aids: north and east from GPS position; down from the barometer (``-(alt - alt₀)``), or from GPS
down while no barometer reading has arrived. The barometer is relative: its first reading is taken as
the current height estimate (0 m down if nothing set the vertical before), so only its changes count.
The first reading of an axis, or the first after a gap longer than ``max_gap_s`` or than the loop's
``1 / kp`` (one correction would overshoot), sets that axis's position (and velocity, from GPS
velocity); until then the axis integrates the accelerometer from rest at 0.

Bad input: a non-finite or non-positive ``dt_s`` ignores the sample (state returned unchanged); a
non-finite acceleration propagates at constant velocity; ``dt_s > max_gap_s`` is not integrated (a
stale acceleration over seconds), and the next readings re-set their axes; a NaN/Inf reading or
component is no reading.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from groundstation.position import design
from groundstation.readings import optional_rows

# The design inputs of the defaults (design.crossover_rad_s). Accelerometer error in NED, below
# 0.1 Hz (variance of 10-s means × 10 s), of AHF's attitude on the simulated flight (seeds 11-12, not
# the tests' or the experiment's): horizontally ≈ 1 m/s²/√Hz, g × the tilt error in manoeuvres;
# vertically ≈ 0.1 (the tilt error enters to second order). In a hover, or with the true attitude,
# it is 10-100 times lower and a lower crossover would smooth more. Aids: a barometer of 0.17 m σ
# at 25 Hz (2 Pa, a BMP280 in high resolution); a GPS of 1 m σ position, 0.05 m/s σ velocity, 10 Hz.
ACC_ERROR_HORIZONTAL_M_S2_RT_HZ = 1.0
ACC_ERROR_VERTICAL_M_S2_RT_HZ = 0.1
BARO_NOISE_M, BARO_RATE_HZ = 0.17, 25.0
GPS_POS_NOISE_M, GPS_VEL_NOISE_M_S, GPS_RATE_HZ = 1.0, 0.05, 10.0


def _gps_vel_crossover_rad_s() -> float:
    """The velocity rule gives ~60 rad/s; a correction held over a 0.1 s GPS interval stays accurate
    only with kv Δ = 2ζω Δ well below 1, so ω is limited to kv Δ = 0.5."""
    rule = design.crossover_rad_s(ACC_ERROR_HORIZONTAL_M_S2_RT_HZ, GPS_VEL_NOISE_M_S, GPS_RATE_HZ, aid_order=1)
    return min(rule, 0.5 * GPS_RATE_HZ / (2.0 * design.SQRT_HALF))


@dataclasses.dataclass(frozen=True)
class SingleChannelSettings:
    """Proportional loops only (seed 004 algorithm 2). Crossovers ω in rad/s (``design``)."""

    # vertical loop aided by the barometer
    baro_crossover_rad_s: float = design.crossover_rad_s(ACC_ERROR_VERTICAL_M_S2_RT_HZ, BARO_NOISE_M, BARO_RATE_HZ)
    # horizontal loops aided by GPS position
    gps_crossover_rad_s: float = design.crossover_rad_s(ACC_ERROR_HORIZONTAL_M_S2_RT_HZ, GPS_POS_NOISE_M, GPS_RATE_HZ)
    # vertical loop aided by GPS down, while no barometer reading has arrived
    gps_down_crossover_rad_s: float = design.crossover_rad_s(ACC_ERROR_VERTICAL_M_S2_RT_HZ, GPS_POS_NOISE_M, GPS_RATE_HZ)
    damping: float = design.SQRT_HALF  # ζ of the loops' second-order poles, dimensionless
    max_gap_s: float = 1.0  # longer without a reading (or a longer dt_s): re-set from the next reading


@dataclasses.dataclass(frozen=True)
class DualChannelSettings(SingleChannelSettings):
    """Proportional + integral loops, and the GPS velocity loop (seed 004 algorithm 3)."""

    gps_vel_crossover_rad_s: float = _gps_vel_crossover_rad_s()  # velocity loops, all three axes
    bias_pole_ratio: float = 0.25  # ρ: the bias pole at ρω, dimensionless (design)


class PositionFilter:
    """Shared prediction, correction and input guards; subclasses set ``Settings`` and ``_gains``."""

    Settings: type = SingleChannelSettings

    def __init__(self, settings=None):
        self.settings = self.Settings() if settings is None else settings
        s = self.settings
        if not s.max_gap_s > 0:
            raise ValueError(f"max_gap_s must be positive, not {s.max_gap_s!r}")
        self.baro_gains = self._gains(s.baro_crossover_rad_s, s.damping)
        self.gps_gains = self._gains(s.gps_crossover_rad_s, s.damping)
        self.gps_down_gains = self._gains(s.gps_down_crossover_rad_s, s.damping)
        self.vel_gains = self._velocity_gains(s)
        self.reset()

    def _gains(self, omega_rad_s: float, damping: float) -> design.Gains:
        raise NotImplementedError

    def _velocity_gains(self, settings) -> design.VelocityGains | None:
        return None

    def reset(self) -> None:
        """Forget everything: rest at the origin, no bias, no reading seen."""
        self._p = [0.0, 0.0, 0.0]
        self._v = [0.0, 0.0, 0.0]
        self._b = [0.0, 0.0, 0.0]
        self._since_pos_s = [math.inf] * 3  # time since each axis's last position reading
        self._since_vel_s = [math.inf] * 3
        self._baro_offset_m = None  # altitude reading that corresponds to 0 m down

    @property
    def bias_ned_m_s2(self) -> tuple[float, float, float]:
        """The accelerometer bias estimate b̂ (NED, m/s²); zero for the single channel."""
        return tuple(self._b)

    def step(self, acc_ned_m_s2, dt_s, baro_alt_m=None, gps_pos_ned_m=None, gps_vel_ned_m_s=None):
        """One sample: returns ``(pos_ned_m, vel_ned_m_s)``, each a tuple of 3 floats.

        ``acc_ned_m_s2`` NED linear acceleration (``acceleration.linear_acc_ned_m_s2``); ``dt_s`` since
        the previous sample; the readings that arrived on this sample, or None.
        """
        p, v, b = self._p, self._v, self._b
        if not 0.0 < dt_s < math.inf:
            return tuple(p), tuple(v)
        if dt_s <= self.settings.max_gap_s:
            acc = acc_ned_m_s2 if _finite(acc_ned_m_s2) else b  # no acceleration: constant velocity
            half = 0.5 * dt_s * dt_s
            for i in range(3):
                a = acc[i] - b[i]
                p[i] += v[i] * dt_s + a * half
                v[i] += a * dt_s
        since_p, since_v = self._since_pos_s, self._since_vel_s
        for i in range(3):
            since_p[i] += dt_s
            since_v[i] += dt_s
        down = None
        if baro_alt_m is not None and _finite((baro_alt_m,)):
            if self._baro_offset_m is None:
                self._baro_offset_m = baro_alt_m + (p[2] if since_p[2] < math.inf else 0.0)
            down = self._baro_offset_m - baro_alt_m
        gps = gps_pos_ned_m if gps_pos_ned_m is not None else (None, None, None)
        if self._baro_offset_m is None:
            down = gps[2]
        for i, z, gains in ((0, gps[0], self.gps_gains), (1, gps[1], self.gps_gains), (2, down, self._vertical_gains())):
            if z is not None and z - z == 0.0:
                self._correct_position(i, z, gains)
        if gps_vel_ned_m_s is not None and self.vel_gains is not None:
            for i, u in enumerate(gps_vel_ned_m_s):
                if u - u == 0.0:
                    self._correct_velocity(i, u)
        return tuple(p), tuple(v)

    def _vertical_gains(self) -> design.Gains:
        return self.gps_down_gains if self._baro_offset_m is None else self.baro_gains

    def _correct_position(self, i: int, z: float, gains: design.Gains) -> None:
        delta_s = self._since_pos_s[i]
        self._since_pos_s[i] = 0.0
        # First reading, or a gap the loop cannot close in one correction (kp Δ > 1 overshoots): re-set.
        if delta_s > self.settings.max_gap_s or gains.kp_1_s * delta_s > 1.0:
            self._p[i] = z
            return
        e = z - self._p[i]
        self._p[i] += gains.kp_1_s * e * delta_s
        self._v[i] += gains.kv_1_s2 * e * delta_s
        self._b[i] -= gains.ki_1_s3 * e * delta_s

    def _correct_velocity(self, i: int, u: float) -> None:
        delta_s = self._since_vel_s[i]
        self._since_vel_s[i] = 0.0
        if delta_s > self.settings.max_gap_s or self.vel_gains.kv_1_s * delta_s > 1.0:
            self._v[i] = u
            return
        e = u - self._v[i]
        self._v[i] += self.vel_gains.kv_1_s * e * delta_s
        self._b[i] -= self.vel_gains.ki_1_s2 * e * delta_s

    def run(self, acc_ned_m_s2, dt_s, baro_alt_m=None, gps_pos_ned_m=None, gps_vel_ned_m_s=None):
        """Step through arrays: ``acc_ned_m_s2`` (N, 3), ``dt_s`` (N,) or a scalar, ``baro_alt_m`` (N,),
        ``gps_pos_ned_m`` and ``gps_vel_ned_m_s`` (N, 3), NaN on samples without a reading.

        Continues from the current state (``reset()`` first for a fresh start). Returns ``(pos_ned_m,
        vel_ned_m_s)``, two (N, 3) arrays whose row k is exactly what ``step`` returns for sample k.
        """
        acc = np.asarray(acc_ned_m_s2, dtype=float).reshape(-1, 3)
        n = len(acc)
        dt = np.broadcast_to(np.asarray(dt_s, dtype=float), (n,)).tolist()
        baro = optional_rows(baro_alt_m, n, 1, "baro_alt_m")
        gps_pos = optional_rows(gps_pos_ned_m, n, 3, "gps_pos_ned_m")
        gps_vel = optional_rows(gps_vel_ned_m_s, n, 3, "gps_vel_ned_m_s")
        out = np.empty((n, 6))
        step = self.step
        for k, (a, d, h, z, u) in enumerate(zip(acc.tolist(), dt, baro, gps_pos, gps_vel)):
            p, v = step(a, d, None if h is None else h[0], z, u)
            out[k, :3] = p
            out[k, 3:] = v
        return out[:, :3], out[:, 3:]


class SingleChannel(PositionFilter):
    """Seed 004 algorithm 2: proportional correction of position and velocity from the position error."""

    Settings = SingleChannelSettings

    def _gains(self, omega_rad_s, damping):
        return design.single_channel_gains(omega_rad_s, damping)


class DualChannel(PositionFilter):
    """Seed 004 algorithm 3: proportional + integral (accelerometer bias) loops, plus GPS velocity."""

    Settings = DualChannelSettings

    def _gains(self, omega_rad_s, damping):
        return design.dual_channel_gains(omega_rad_s, damping, self.settings.bias_pole_ratio)

    def _velocity_gains(self, settings):
        return design.velocity_gains(settings.gps_vel_crossover_rad_s, settings.damping)


def _finite(values) -> bool:
    total = sum(values)
    return total - total == 0.0  # False for any NaN or Inf

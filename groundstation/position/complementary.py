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

from groundstation.estimation.compiled_cache import use_user_cache

use_user_cache()  # before numba is imported: ``_run`` is compiled once per user, as the estimators are
from numba import njit  # noqa: E402
from numba.extending import register_jitable  # noqa: E402

from groundstation.position import design  # noqa: E402

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
        self._state = [0.0] * 9 + [math.inf] * 6 + [math.nan]  # ``advance``'s layout; a list: cheapest per ``step``

    @property
    def bias_ned_m_s2(self) -> tuple[float, float, float]:
        """The accelerometer bias estimate b̂ (NED, m/s²); zero for the single channel."""
        return tuple(self._state[_B : _B + 3])

    def _gains_row(self) -> list[float]:
        velocity = self.vel_gains if self.vel_gains is not None else (0.0, 0.0)
        return [*self.baro_gains, *self.gps_gains, *self.gps_down_gains, *velocity,
                float(self.vel_gains is not None), self.settings.max_gap_s]  # fmt: skip

    def step(self, acc_ned_m_s2, dt_s, baro_alt_m=None, gps_pos_ned_m=None, gps_vel_ned_m_s=None):
        """One sample: returns ``(pos_ned_m, vel_ned_m_s)``, each a tuple of 3 floats.

        ``acc_ned_m_s2`` NED linear acceleration (``acceleration.linear_acc_ned_m_s2``); ``dt_s`` since
        the previous sample; the readings that arrived on this sample, or None.
        """
        s = self._state
        advance(s, self._gains_row(), acc_ned_m_s2, dt_s, math.nan if baro_alt_m is None else baro_alt_m,
                _NONE if gps_pos_ned_m is None else gps_pos_ned_m, _NONE if gps_vel_ned_m_s is None else gps_vel_ned_m_s)
        return (s[0], s[1], s[2]), (s[3], s[4], s[5])

    def run(self, acc_ned_m_s2, dt_s, baro_alt_m=None, gps_pos_ned_m=None, gps_vel_ned_m_s=None):
        """Step through arrays: ``acc_ned_m_s2`` (N, 3), ``dt_s`` (N,) or a scalar, ``baro_alt_m`` (N,),
        ``gps_pos_ned_m`` and ``gps_vel_ned_m_s`` (N, 3), NaN on samples without a reading.

        Continues from the current state (``reset()`` first for a fresh start). Returns ``(pos_ned_m,
        vel_ned_m_s)``, two (N, 3) arrays whose row k is exactly what ``step`` returns for sample k: the
        same ``advance``, compiled.
        """
        acc = np.ascontiguousarray(acc_ned_m_s2, dtype=float).reshape(-1, 3)
        n = len(acc)
        dt = np.ascontiguousarray(np.broadcast_to(np.asarray(dt_s, dtype=float), (n,)))
        baro = _rows(baro_alt_m, n, 1, "baro_alt_m")[:, 0]
        gps_pos = _rows(gps_pos_ned_m, n, 3, "gps_pos_ned_m")
        gps_vel = _rows(gps_vel_ned_m_s, n, 3, "gps_vel_ned_m_s")
        out = np.empty((n, 6))
        state = np.array(self._state)
        _run(state, np.array(self._gains_row()), acc, dt, baro, gps_pos, gps_vel, out)
        self._state = state.tolist()
        return out[:, :3], out[:, 3:]


def _rows(values, n: int, width: int, name: str) -> np.ndarray:
    """(n, width) float rows of an optional input: all NaN (no reading) for None."""
    if values is None:
        return np.full((n, width), math.nan)
    rows = np.ascontiguousarray(values, dtype=float).reshape(-1, width)
    if len(rows) != n:
        raise ValueError(f"{name} has {len(rows)} rows of {width}, expected {n}")
    return rows


# ``advance``'s state: position, velocity, bias (NED), the time since each axis's last position and
# velocity reading, the barometer offset (NaN: none yet). Its gains: the barometer's, GPS position's
# and GPS down's (kp, kv, ki each), GPS velocity's (kv, ki), whether that loop exists, max_gap_s.
_P, _V, _B, _SINCE_P, _SINCE_V, _BARO_OFFSET = 0, 3, 6, 9, 12, 15
_G_BARO, _G_GPS, _G_DOWN, _G_VEL, _G_HAS_VEL, _G_MAX_GAP = 0, 3, 6, 9, 11, 12
_NONE = (math.nan, math.nan, math.nan)


@register_jitable  # interpreted by ``step`` on lists (live, per sample), compiled in ``_run`` on arrays
def advance(s, g, acc, dt_s, baro_alt_m, gps_pos, gps_vel):
    """One sample of the filter on its state ``s`` (in place): prediction, then the corrections of the
    readings given (NaN: none). The module's docstring has the equations."""
    if not 0.0 < dt_s < math.inf:
        return
    if dt_s <= g[_G_MAX_GAP]:
        total = acc[0] + acc[1] + acc[2]
        measured = total - total == 0.0  # False for any NaN or Inf: no acceleration, constant velocity
        half = 0.5 * dt_s * dt_s
        for i in range(3):
            a = (acc[i] if measured else s[_B + i]) - s[_B + i]
            s[_P + i] += s[_V + i] * dt_s + a * half
            s[_V + i] += a * dt_s
    for i in range(3):
        s[_SINCE_P + i] += dt_s
        s[_SINCE_V + i] += dt_s
    down = math.nan
    if baro_alt_m - baro_alt_m == 0.0:
        if math.isnan(s[_BARO_OFFSET]):  # the first reading is the current height (0 m before any)
            s[_BARO_OFFSET] = baro_alt_m + (s[_P + 2] if s[_SINCE_P + 2] < math.inf else 0.0)
        down = s[_BARO_OFFSET] - baro_alt_m
    vertical = _G_BARO
    if math.isnan(s[_BARO_OFFSET]):  # no barometer yet: GPS down aids the vertical
        down = gps_pos[2]
        vertical = _G_DOWN
    for i in range(3):
        z = down if i == 2 else gps_pos[i]
        if z - z == 0.0:
            _correct(s, g, i, _P, _SINCE_P, z, vertical if i == 2 else _G_GPS, _V)
    if g[_G_HAS_VEL] != 0.0:
        for i in range(3):
            if gps_vel[i] - gps_vel[i] == 0.0:
                _correct(s, g, i, _V, _SINCE_V, gps_vel[i], _G_VEL, -1)


@register_jitable
def _correct(s, g, i, value, since, z, k, rate):
    """Axis ``i`` of the state's ``value`` (position or velocity) corrected by the reading ``z`` with the
    gains from ``g[k]``: into the value, into its ``rate`` (velocity; -1 for none), out of the bias."""
    delta_s = s[since + i]
    s[since + i] = 0.0
    # First reading, or a gap the loop cannot close in one correction (k Δ > 1 overshoots): re-set.
    if delta_s > g[_G_MAX_GAP] or g[k] * delta_s > 1.0:
        s[value + i] = z
        return
    e = z - s[value + i]
    s[value + i] += g[k] * e * delta_s
    if rate >= 0:
        s[rate + i] += g[k + 1] * e * delta_s
        k += 1
    s[_B + i] -= g[k + 1] * e * delta_s


@njit(cache=True)
def _run(s, g, acc, dt, baro, gps_pos, gps_vel, out):  # pragma: no cover - compiled (tests compare it with step)
    for k in range(len(acc)):
        advance(s, g, acc[k], dt[k], baro[k], gps_pos[k], gps_vel[k])
        for j in range(6):
            out[k, j] = s[j]


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

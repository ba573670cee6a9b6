"""GPS-aided unscented attitude filters of seed 001: ``ukf`` (standard) and ``sssrukf`` (its square root
with spherical simplex sigma points). The digest's §4 SSSRUKF bullet; the paper's sections in brackets.

Model (§1.1, §1.2, eq. 1-8):

- state ``x = q`` (w, x, y, z), body -> NED; process: the gyro quaternion kinematics ``q̇ = ½ q ⊗ [0, ω]``
  integrated over each sample (``integrate_rate``, eq. 2), additive process noise;
- accelerometer specific force ``f = v̇_b + ω × v_b - g_b`` (eq. 3): the manoeuvre acceleration
  ``a_man = v̇_b + ω × v_b`` is taken from the GPS velocity (eq. 5-6): ``v_b`` is the latest fix's NED
  velocity rotated into the body with the current estimate, ``v̇_b`` the finite difference of
  consecutive fixes' body-frame velocities (each rotated with the estimate at its fix). ``ω × v_b``
  uses the current gyro, so a turn's centripetal term has no GPS lag. (``Rᵀ Δv_NED/Δt`` is already the
  whole ``a_man``: adding ``ω × v_b`` to it would count the centripetal term twice.)
- measurements (eq. 7): pitch and roll of ``f - a_man`` (``acc_pitch_roll``, eq. 4) on every sample
  with a usable accelerometer, and the dual-antenna GPS heading as yaw on samples where a fix with a
  heading arrives; all three as the ZYX Euler angles of the state. Without a GPS velocity (none yet,
  or none for ``gps_timeout_s``) the raw accelerometer tilt is used with ``uncompensated_tilt_noise_rad``.

The 4-D state and its norm (the paper's choice, "both with four-dimensional state"): the sigma points
are propagated with the normalising ``integrate_rate``, so their spread keeps no component along
``q``; the process noise is isotropic in the quaternion, ``Q = (½ σ_g dt)² I₄``, which is exactly the
gyro noise ``(½ σ_g dt)² Ξ Ξᵀ`` on the three rotation directions (``Ξ Ξᵀ + q qᵀ = I`` for unit q) plus
the same small variance along ``q`` itself. That radial variance keeps P (and its Cholesky factor)
positive definite, and is harmless: the measurements are Euler angles computed scale-free from
unnormalised quaternions, so they do not see it. The estimate is normalised after each update.
A 3-D error state would avoid the radial direction altogether but changes the sigma-point counts
(7 vs 5 instead of the paper's 9 vs 6) on which the paper's run-time comparison rests.

The first heading sets yaw outright (as the first accelerometer sample sets pitch and roll): a yaw
innovation of up to 180° is outside what a linearised quaternion update can take in one step.

Noise defaults (per sample at 100 Hz, 1σ): gyro 0.005 °/s/√Hz (MPU-6050 datasheet table 6.1) plus
the unestimated bias (see ``gyro_noise_rad_s``); accelerometer 400 µg/√Hz (table 6.2) -> 2.8 mg;
GPS velocity 0.05 m/s and heading 0.5° (``sim.extra_sensors.AuxSettings``). The GPS velocity noise,
differenced over the fix interval Δt_fix, gives the compensated tilt an error of √2 σ_v / (Δt_fix g)
rad which is reused on every sample until the next fix: its variance is charged Δt_fix / dt times
per sample, so one fix interval carries what one fix is worth.
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, NamedTuple

import numpy as np

from groundstation.estimation import sigma_points as sp
from groundstation.estimation import small_linalg as sl
from groundstation.estimation.base import CommonSettings, Estimator, integrate_rate
from groundstation.estimation.tilt import acc_pitch_roll, wrap_pi
from groundstation.units import STANDARD_GRAVITY_M_S2 as G

# diag.status bits of these filters (above base's)
GPS_COMPENSATED = 128  # the tilt measurement had the manoeuvre acceleration removed
HEADING_USED = 256  # a GPS heading was a measurement on this sample (or set yaw, the first time)
COVARIANCE_RESET = 512  # the covariance was re-initialised: it lost positive definiteness, or the filter was lost

_N = 4
_COS_PITCH_MIN = 0.05  # roll noise grows as 1/cos θ; capped near ±90° pitch, where roll is undefined


@dataclasses.dataclass(frozen=True)
class GpsUkfSettings(CommonSettings):
    # σ_g, rad/s per sample: the datasheet's white noise (0.005 °/s/√Hz × √50 Hz = 0.035 °/s) is far
    # below the bias the filter does not estimate: the ZRO temperature drift (±20 °/s over 125 °C, 3σ)
    # over a few °C of warm-up after calibration leaves ~0.1-0.3 °/s; σ_g covers 0.3 °/s.
    gyro_noise_rad_s: float = math.radians(0.3)
    acc_noise_g: float = 400e-6 * math.sqrt(50.0)  # accelerometer noise per sample at 100 Hz, g (≈ rad of tilt)
    gps_velocity_noise_m_s: float = 0.05  # σ per axis of a fix's velocity
    heading_noise_rad: float = math.radians(0.5)  # σ of the dual-antenna heading
    uncompensated_tilt_noise_rad: float = 0.1  # tilt noise without GPS: covers ~0.1 g of manoeuvre
    gps_timeout_s: float = 0.5  # no fix for longer: the velocity is stale, compensation stops
    initial_attitude_noise_rad: float = 0.05  # σ of the initial attitude (tilt from gravity; yaw is set by the first heading)
    # Lost: the innovation above this (rad) for lost_time_s means the covariance no longer describes the
    # error (e.g. after the gyro sat at full scale, where the true rate is unknown): it is re-initialised,
    # so the next measurements pull the estimate back at the initial gain instead of over minutes.
    lost_innovation_rad: float = 0.2
    lost_time_s: float = 0.25
    ut_alpha: float = 1.0  # sigma-point spread (scaled UT, ref. [8])
    ut_beta: float = 2.0  # prior-distribution term; 2 is optimal for a Gaussian


@dataclasses.dataclass(frozen=True)
class UkfSettings(GpsUkfSettings):
    ut_kappa: float = 0.0  # secondary scaling of the symmetric set; λ = α² (n + κ) - n


@dataclasses.dataclass(frozen=True)
class SssrukfSettings(GpsUkfSettings):
    simplex_w0: float = 0.0  # weight of the centre point, 0 <= W0 < 1 (§2.1 step 1)


class GpsUkfDiagnostics(NamedTuple):
    status: int
    acc_pitch_rad: float  # pitch of the (compensated) accelerometer on its last usable sample
    acc_roll_rad: float  # roll of the same
    manoeuvre_acc_m_s2: float  # |a_man| removed from the accelerometer (0 without GPS)
    innovation_rad: float  # norm of the angle innovation of the last update (0 if none)
    p_trace: float  # trace of the quaternion covariance


def euler_angles(q, yaw: bool = True) -> tuple[float, ...]:
    """ZYX Euler angles (pitch, roll, yaw) of a quaternion (w, x, y, z) of any norm, plain floats;
    (pitch, roll) only without ``yaw`` (a tilt-only update needs no third atan2 per sigma point)."""
    w, x, y, z = q
    n2 = w * w + x * x + y * y + z * z
    sin_pitch = 2.0 * (w * y - x * z) / n2
    sin_pitch = -1.0 if sin_pitch < -1.0 else 1.0 if sin_pitch > 1.0 else sin_pitch
    pitch_roll = math.asin(sin_pitch), math.atan2(2.0 * (w * x + y * z), w * w - x * x - y * y + z * z)
    return pitch_roll + (math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z),) if yaw else pitch_roll


def euler_of(chi: np.ndarray) -> np.ndarray:
    """ZYX Euler angles (3, L) rows (pitch, roll, yaw) of quaternion columns (4, L), any norm."""
    return np.array([euler_angles(c) for c in np.asarray(chi, dtype=float).T.tolist()]).reshape(-1, 3).T


def ned_to_body(q, v):
    """``R(q)ᵀ v`` for a unit quaternion tuple and a 3-tuple (plain floats)."""
    w, x, y, z = q
    vn, ve, vd = v
    return (
        (1 - 2 * (y * y + z * z)) * vn + 2 * (x * y + w * z) * ve + 2 * (x * z - w * y) * vd,
        2 * (x * y - w * z) * vn + (1 - 2 * (x * x + z * z)) * ve + 2 * (y * z + w * x) * vd,
        2 * (x * z + w * y) * vn + 2 * (y * z - w * x) * ve + (1 - 2 * (x * x + y * y)) * vd,
    )


class _GpsUkf(Estimator):
    """What both filters share; subclasses pick the sigma-point set and dense or square-root steps."""

    needs = frozenset({"gps"})  # without GPS velocity they are slow tilt filters at ~100x the others' cost

    Diagnostics = GpsUkfDiagnostics
    _square_root: ClassVar[bool]

    def __init__(self, settings=None):
        super().__init__(settings)
        self._sigma = self._sigma_set(self.settings)

    def _reset_state(self):
        self._cov = self._initial_cov((1.0, 0.0, 0.0, 0.0))  # P (ukf) or its lower Cholesky factor S (sssrukf)
        self._starting = True  # the next _set_attitude is a start, not a re-initialisation after a gap
        self._yaw_known = False
        self._since_fix_s = math.inf  # time since the last GPS velocity
        self._fix_interval_s = math.inf  # between the last two
        self._v_ned = None  # last GPS velocity, m/s
        self._v_body_at_fix = None  # the same rotated into the body at its fix
        self._dv_body = None  # v̇_b, m/s²
        self._acc_pr = (0.0, 0.0)
        self._a_man = 0.0
        self._innovation = 0.0
        self._lost_s = 0.0

    def _set_attitude(self, q):
        # A start takes the initial covariance about q. After a gap (base.REINITIALISED) the covariance is
        # kept: the tilt from gravity is what a tilt measurement would have said, and a restarted covariance
        # let the next noisy GPS-compensated measurements swing a still estimate by 1.7° (test_intervals.py).
        self._q = q
        if self._starting:
            self._cov = self._initial_cov(q)
            self._starting = False

    def _initial_cov(self, q):
        qv = np.array(q)
        std = 0.5 * self.settings.initial_attitude_noise_rad  # a rotation θ moves q by θ/2
        p = std * std * (np.eye(_N) - np.outer(qv, qv)) + (1e-3 * std) ** 2 * np.outer(qv, qv)
        return (np.linalg.cholesky(p) if self._square_root else p).tolist()

    def _diagnostics(self, status):
        cov = self._cov
        trace = sum(sl.dot(r, r) for r in cov) if self._square_root else sum(cov[i][i] for i in range(_N))
        return GpsUkfDiagnostics(status, *self._acc_pr, self._a_man, self._innovation, trace)

    def _take_fix(self):
        """Book a new GPS velocity: the body-frame derivative v̇_b between consecutive fixes (eq. 5)."""
        fix = self._gps
        if fix is None:
            return
        v_ned = (fix.vel_n_m_s, fix.vel_e_m_s, fix.vel_d_m_s)
        if not all(math.isfinite(c) for c in v_ned):
            return
        v_body = ned_to_body(self._q, v_ned)
        if self._v_body_at_fix is not None and self._since_fix_s <= self.settings.gps_timeout_s:
            h = self._since_fix_s
            self._dv_body = tuple((a - b) / h for a, b in zip(v_body, self._v_body_at_fix))
            self._fix_interval_s = h
        else:
            self._dv_body = None
        self._v_ned, self._v_body_at_fix, self._since_fix_s = v_ned, v_body, 0.0

    def _tilt_measurement(self, q_pred, gx, gy, gz, ax, ay, az, dt_s):
        """(pitch, roll, σ²_pitch, σ²_roll, compensated) of the accelerometer, or None if unusable."""
        s = self.settings
        if self._dv_body is not None and self._since_fix_s <= s.gps_timeout_s:
            vx, vy, vz = ned_to_body(q_pred, self._v_ned)
            dx, dy, dz = self._dv_body
            a_man = (dx + gy * vz - gz * vy, dy + gz * vx - gx * vz, dz + gx * vy - gy * vx)  # eq. 5
            ax, ay, az = ax - a_man[0] / G, ay - a_man[1] / G, az - a_man[2] / G
            self._a_man = math.sqrt(a_man[0] ** 2 + a_man[1] ** 2 + a_man[2] ** 2)
            var = s.acc_noise_g**2 + 2.0 * s.gps_velocity_noise_m_s**2 / (self._fix_interval_s * dt_s * G * G)
            compensated = True
        else:
            self._a_man = 0.0
            var = s.uncompensated_tilt_noise_rad**2
            compensated = False
        if not self._acc_min2 <= ax * ax + ay * ay + az * az < math.inf:
            return None
        pitch, roll = acc_pitch_roll(ax, ay, az)
        self._acc_pr = (pitch, roll)
        cos_pitch = max(abs(math.cos(pitch)), _COS_PITCH_MIN)
        return pitch, roll, var, var / (cos_pitch * cos_pitch), compensated

    def _set_yaw(self, x, heading_rad):
        """Turn the state about NED z so that its yaw is ``heading_rad``."""
        half = 0.5 * wrap_pi(heading_rad - euler_angles(x)[2])
        c, s = math.cos(half), math.sin(half)
        w, qx, qy, qz = x
        return [c * w - s * qz, c * qx - s * qy, c * qy + s * qx, c * qz + s * w]

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        self._since_fix_s += dt_s
        self._take_fix()
        try:
            x, cov = self._filter(gx, gy, gz, ax, ay, az, acc_ok, dt_s)
        except np.linalg.LinAlgError:
            x = list(integrate_rate(self._q, gx, gy, gz, dt_s))
            cov, status = self._initial_cov(tuple(x)), status | COVARIANCE_RESET
        status |= self._status
        self._lost_s = self._lost_s + dt_s if self._innovation > self.settings.lost_innovation_rad else 0.0
        if self._lost_s >= self.settings.lost_time_s:
            norm = math.sqrt(sl.dot(x, x))
            cov, status, self._lost_s = self._initial_cov(tuple(c / norm for c in x)), status | COVARIANCE_RESET, 0.0
        if self._gps is not None and math.isfinite(self._gps.heading_rad) and not self._yaw_known:
            x = self._set_yaw(x, self._gps.heading_rad)
            self._yaw_known = True
            status |= HEADING_USED
        norm = math.sqrt(sl.dot(x, x))
        self._q, self._cov = tuple(c / norm for c in x), cov
        return self._q, self._diagnostics(status)

    def _filter(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s):
        """One predict + update; ``self._status`` gets this sample's measurement flags."""
        s, sigma, sr = self.settings, self._sigma, self._square_root
        self._status = 0
        self._innovation = 0.0
        factor = self._cov if sr else sl.cholesky(self._cov)
        chi = [integrate_rate(p, gx, gy, gz, dt_s) for p in sp.points_lists(self._q, factor, sigma)]  # eq. 2
        q_noise = 0.5 * s.gyro_noise_rad_s * dt_s
        if sr:
            x, cov = sp.sqrt_time_update_lists(chi, sigma, sl.diag([q_noise] * _N))
        else:
            x, cov = sp.time_update_lists(chi, sigma, sl.diag([q_noise * q_noise] * _N))
        norm = math.sqrt(sl.dot(x, x))
        q_pred = tuple(c / norm for c in x)
        rows, y, var = [], [], []
        tilt = self._tilt_measurement(q_pred, gx, gy, gz, ax, ay, az, dt_s) if acc_ok else None
        if tilt is not None:
            rows += [0, 1]
            y += tilt[:2]
            var += tilt[2:4]
            self._status |= GPS_COMPENSATED if tilt[4] else 0
        fix = self._gps
        if fix is not None and self._yaw_known and math.isfinite(fix.heading_rad):
            rows.append(2)
            y.append(fix.heading_rad)
            var.append(s.heading_noise_rad**2)
            self._status |= HEADING_USED
        if not rows:
            return x, cov
        factor = cov if sr else sl.cholesky(cov)
        chi = sp.points_lists(x, factor, sigma)
        angles = list(zip(*[euler_angles(p, 2 in rows) for p in chi]))  # pitch, roll (, yaw) rows
        y_sigma = [angles[i] for i in rows]
        if sr:
            x, cov, innovation = sp.sqrt_measurement_update_lists(x, cov, chi, y_sigma, y, sl.diag([math.sqrt(v) for v in var]), sigma)
        else:
            x, cov, innovation = sp.measurement_update_lists(x, cov, chi, y_sigma, y, sl.diag(var), sigma)
        self._innovation = math.sqrt(sl.dot(innovation, innovation))
        return x, cov


class Ukf(_GpsUkf):
    """Standard UKF: 2n + 1 = 9 symmetric sigma points, full covariance, Cholesky twice a sample."""

    name = "ukf"
    label = "UKF"
    colour = "rose"
    Settings = UkfSettings
    _square_root = False

    @staticmethod
    def _sigma_set(s):
        return sp.symmetric(_N, s.ut_alpha, s.ut_beta, s.ut_kappa)


class Sssrukf(_GpsUkf):
    """Seed 001's SSSRUKF: square-root UKF, additive noise, n + 2 = 6 spherical simplex sigma points."""

    name = "sssrukf"
    label = "SSSRUKF"
    colour = "purple"
    Settings = SssrukfSettings
    _square_root = True

    @staticmethod
    def _sigma_set(s):
        return sp.spherical_simplex(_N, s.simplex_w0, s.ut_alpha, s.ut_beta)

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
- measurements (eq. 7): gravity from ``f - a_man`` on every sample with a usable accelerometer, and the
  dual-antenna GPS heading as yaw (ZYX Euler, wrapped) on samples where a fix with a heading arrives.
  Without a GPS velocity (none yet, or none for ``gps_timeout_s``) the raw accelerometer is used with
  ``uncompensated_acc_noise_g``.

Where the gravity measurement departs from the paper: eq. 7 measures pitch and roll, eq. 4's angles of
``f - a_man``. Here the measurement is the down direction in the body, ``-(f - a_man)`` in g as it is
(not normalised), against ``h(q) = R(q)ᵀ [0, 0, 1]`` (as ekf): linear in the reading, so the update
averages it and zero-mean shaking averages out. Eq. 4's angles are not: the mean of atan2 is not the
atan2 of the mean, and under ±3 g of vibration at 100 Hz the per-sample angles average 30-45° off
gravity's (tests/estimation/test_adversaries.py, ``vibration_100hz``: both filters ended 45° off). With
the compensation working the two agree to first order (the reading is gravity of norm 1 g plus noise);
near ±90° pitch, where eq. 4's roll is undefined, the direction has no singularity.

The 4-D state and its norm (the paper's choice, "both with four-dimensional state"): the sigma points
are propagated with the normalising ``integrate_rate``, so their spread keeps no component along
``q``; the process noise is isotropic in the quaternion, ``Q = (½ σ_g dt)² I₄``, which is exactly the
gyro noise ``(½ σ_g dt)² Ξ Ξᵀ`` on the three rotation directions (``Ξ Ξᵀ + q qᵀ = I`` for unit q) plus
the same small variance along ``q`` itself. That radial variance keeps P (and its Cholesky factor)
positive definite, and is harmless: the measurements (the down direction over ``|q|²``, the yaw angle)
are computed scale-free from unnormalised quaternions, so they do not see it. The estimate is normalised
after each update.
A 3-D error state would avoid the radial direction altogether but changes the sigma-point counts
(7 vs 5 instead of the paper's 9 vs 6) on which the paper's run-time comparison rests.

The first heading sets yaw outright (as the first accelerometer sample sets pitch and roll): a yaw
innovation of up to 180° is outside what a linearised quaternion update can take in one step.

Noise defaults (per sample at 100 Hz, 1σ): gyro 0.005 °/s/√Hz (MPU-6050 datasheet table 6.1) plus
the unestimated bias (see ``gyro_noise_rad_s``); accelerometer 400 µg/√Hz (table 6.2) -> 2.8 mg;
GPS velocity 0.05 m/s and heading 0.5° (``sim.extra_sensors.AuxSettings``). The GPS velocity noise,
differenced over the fix interval Δt_fix, gives the compensated tilt an error of √2 σ_v / (Δt_fix g)
g which is reused on every sample until the next fix: its variance is charged Δt_fix / dt times
per sample, so one fix interval carries what one fix is worth.

Compiled (base.py's ``CompiledEstimator``, ``gps_aided``): one kernel for both, ``p[_SQUARE_ROOT]`` choosing
the dense steps (P, two Choleskys a sample) or the square-root ones (S by QR and rank-1 updates, never
re-factorised), each with its own sigma set, so their run-time ratio is the algorithms' (seed 001: 42 %;
measured in bench/bench_estimator_costs.out.md). A failed factorisation or downdate (``ok`` False, a
kernel cannot catch ``LinAlgError``) restarts the covariance (``COVARIANCE_RESET``). The steps work in a
part of the state (the sigma points, the steps' matrices), so neither ``step`` nor ``run`` allocates per
sample; the operations of each step are counted in bench/bench_estimator_costs.py (``ukf_step_costs``).
"""

from __future__ import annotations

import dataclasses
import math
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit
from numba.extending import register_jitable

from groundstation import quaternion
from groundstation.estimation import sigma_points as sp
from groundstation.estimation import small_linalg as sl
from groundstation.estimation.base import (
    INITIALISED, MAG_REJECTED, NO_UPDATE, P_ACC_MIN2, P_OWN, REINITIALISED, STATE_DIAG, CommonSettings, CompiledEstimator, guard, integrate_rate, record, sample, sample_fix, unmanaged,
)
from groundstation.estimation.tilt import acc_pitch_roll, wrap_pi
from groundstation.units import STANDARD_GRAVITY_M_S2 as G

# diag.status bits of these filters, above base's highest (128 was both MAG_REJECTED and GPS_COMPENSATED)
GPS_COMPENSATED = MAG_REJECTED << 1  # the tilt measurement had the manoeuvre acceleration removed
HEADING_USED = MAG_REJECTED << 2  # a GPS heading was a measurement on this sample (or set yaw, the first time)
COVARIANCE_RESET = MAG_REJECTED << 3  # the covariance was re-initialised: it lost positive definiteness, or the filter was lost

_N = 4
_M_MAX = 4  # measurements: gravity's three components, then the heading


@dataclasses.dataclass(frozen=True)
class GpsUkfSettings(CommonSettings):
    # σ_g, rad/s per sample: the datasheet's white noise (0.005 °/s/√Hz × √50 Hz = 0.035 °/s) is far
    # below the bias the filter does not estimate: the ZRO temperature drift (±20 °/s over 125 °C, 3σ)
    # over a few °C of warm-up after calibration leaves ~0.1-0.3 °/s; σ_g covers 0.3 °/s.
    gyro_noise_rad_s: float = math.radians(0.3)
    acc_noise_g: float = 400e-6 * math.sqrt(50.0)  # accelerometer noise per axis and sample at 100 Hz, g
    gps_velocity_noise_m_s: float = 0.05  # σ per axis of a fix's velocity
    heading_noise_rad: float = math.radians(0.5)  # σ of the dual-antenna heading
    uncompensated_acc_noise_g: float = 0.1  # accelerometer noise per axis without GPS: covers ~0.1 g of manoeuvre
    gps_timeout_s: float = 0.5  # no fix for longer: the velocity is stale, compensation stops
    initial_attitude_noise_rad: float = 0.05  # σ of the initial attitude (tilt from gravity; yaw is set by the first heading)
    # Lost: the gravity innovation (g, ≈ rad of tilt), low-passed over lost_time_s, above this means the
    # covariance no longer describes the error (e.g. after the gyro sat at full scale, where the true rate
    # is unknown): it is re-initialised, so the next measurements pull the estimate back at the initial
    # gain instead of over minutes. Low-passed, not per sample: a zero-mean shake of a few g is not being
    # lost (judged raw, ±3 g at 100 Hz restarted the covariance every 0.25 s). The time constant: 1 s, not
    # 0.25 s, as on three BROAD dev trials without GPS (07, 16, 27) a sustained manoeuvre of 0.25 s restarted
    # the covariance into the disturbed reading (inclination RMSE 7.4°, 70°, 8.0° at 0.25 s; 4.0°, 57°, 4.8°
    # at 1 s; 3.7°, 45°, 7.0° at 2 s); after half a second of a saturated gyro (42° off) it still restarts 0.1 s
    # after the spin and is within 1° 10 s later (tests/estimation/test_ukf.py; 21° off without the restart).
    lost_innovation_g: float = 0.2
    lost_time_s: float = 1.0
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
    innovation: float  # norm of the last update's innovation: gravity (g) and heading (rad); 0 if none
    p_trace: float  # trace of the quaternion covariance


# Parameters after the guard's (base.P_OWN): the step kind, the set's size L, the noises, the timeouts,
# then the set's weights and points (room for the symmetric set's 9).
(_SQUARE_ROOT, _COUNT, _GYRO_NOISE, _ACC_VAR, _VEL_VAR2, _UNCOMPENSATED_VAR, _HEADING_VAR, _GPS_TIMEOUT, _INIT_VAR, _INIT_RADIAL_VAR,
 _LOST_INNOVATION, _LOST_TIME) = range(P_OWN, P_OWN + 12)
_L_MAX = 2 * _N + 1
_WM = P_OWN + 12
_WC = _WM + _L_MAX
_SQRT_WC = _WC + _L_MAX
_Z = _SQRT_WC + _L_MAX
_PARAMS = _Z + _N * _L_MAX
# State after q and the guard's: the diagnostics after status, then P (ukf) or its factor S (sssrukf),
# the start flag, whether yaw is known, the time since the last GPS velocity and the interval between
# the last two, that velocity (NED), the same in the body at its fix, v̇_b (NaN: none), the low-passed
# gravity innovation (the lost test).
_ACC_PITCH, _ACC_ROLL, _A_MAN, _INNOVATION, _TRACE = range(STATE_DIAG, STATE_DIAG + 5)
_COV = STATE_DIAG + 5
_STARTING, _YAW_KNOWN, _SINCE_FIX, _FIX_INTERVAL = range(_COV + _N * _N, _COV + _N * _N + 4)
_V_NED = _FIX_INTERVAL + 1
_V_BODY = _V_NED + 3
_DV_BODY = _V_BODY + 3
_LOST = _DV_BODY + 3
# Then the kernel's work space, rewritten on each sample before it is read (in the state so that neither
# ``step`` nor ``run`` allocates per sample): the Cholesky factor of P (ukf), the sigma points, their
# outputs, the noise's diagonal (Q's; then R's), the measurements, and the two steps' own work.
_FACTOR = _LOST + 3
_CHI = _FACTOR + _N * _N
_Y_SIGMA = _CHI + _L_MAX * _N
_NOISE = _Y_SIGMA + _M_MAX * _L_MAX
_Y = _NOISE + max(_N, _M_MAX)
_TIME_WORK = _Y + _M_MAX
_MEASUREMENT_WORK = _TIME_WORK + sp.work_size(_N, _L_MAX, _N)
_STATE_END = _MEASUREMENT_WORK + sp.work_size(_N, _L_MAX, _M_MAX)


@register_jitable
def euler_angles(w, x, y, z, with_yaw):
    """ZYX Euler angles (pitch, roll, yaw) of a quaternion of any norm; yaw 0 without ``with_yaw`` (a
    tilt-only update needs no third atan2 per sigma point)."""
    n2 = w * w + x * x + y * y + z * z
    sin_pitch = 2.0 * (w * y - x * z) / n2
    sin_pitch = -1.0 if sin_pitch < -1.0 else 1.0 if sin_pitch > 1.0 else sin_pitch
    yaw = math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z) if with_yaw else 0.0
    return math.asin(sin_pitch), math.atan2(2.0 * (w * x + y * z), w * w - x * x - y * y + z * z), yaw


@register_jitable
def down_in_body(w, x, y, z):
    """``h(q) = R(q)ᵀ [0, 0, 1]``, NED down in the body, of a quaternion of any norm (``ned_to_body`` of
    (0, 0, 1) over ``|q|²``)."""
    n2 = w * w + x * x + y * y + z * z
    return 2.0 * (x * z - w * y) / n2, 2.0 * (y * z + w * x) / n2, (w * w - x * x - y * y + z * z) / n2


@register_jitable
def ned_to_body(w, x, y, z, vn, ve, vd):
    """``R(q)ᵀ v`` for a unit quaternion and a NED vector."""
    return (
        (1.0 - 2.0 * (y * y + z * z)) * vn + 2.0 * (x * y + w * z) * ve + 2.0 * (x * z - w * y) * vd,
        2.0 * (x * y - w * z) * vn + (1.0 - 2.0 * (x * x + z * z)) * ve + 2.0 * (y * z + w * x) * vd,
        2.0 * (x * z + w * y) * vn + 2.0 * (y * z - w * x) * ve + (1.0 - 2.0 * (x * x + y * y)) * vd,
    )


@register_jitable
def _dot(a):
    acc = 0.0
    for v in a:
        acc += v * v
    return acc


@register_jitable
def _norm(w, x, y, z):
    """``|q|``, summed as ``_dot``."""
    return math.sqrt(w * w + x * x + y * y + z * z)


@register_jitable
def _matrix(state, start, rows, cols):
    """A (rows, cols) view of the state from ``start``."""
    return sl.matrix_view(state, start, rows, cols)


@register_jitable
def _initial_cov(state, p, w, x, y, z):
    """State's covariance (ukf) or its factor (sssrukf) about the unit quaternion ``(w, x, y, z)``: the
    initial attitude noise on the three rotation directions, a small radial variance along q (module
    docstring)."""
    q = (w, x, y, z)
    cov = _matrix(state, _FACTOR if p[_SQUARE_ROOT] != 0.0 else _COV, _N, _N)
    for i in range(_N):
        for j in range(_N):
            qq = q[i] * q[j]
            cov[i, j] = p[_INIT_VAR] * ((1.0 if i == j else 0.0) - qq) + p[_INIT_RADIAL_VAR] * qq
    if p[_SQUARE_ROOT] != 0.0:
        sl.cholesky(cov, _matrix(state, _COV, _N, _N))


@register_jitable
def _start(state, p):
    """The initial covariance about the attitude from gravity, once. (Called from the kernel through here:
    numba compiles a helper called both from a kernel and from another helper twice.)"""
    _initial_cov(state, p, state[0], state[1], state[2], state[3])
    state[_STARTING] = 0.0


@register_jitable
def _trace(state, p):
    """tr P, from P or from S (the sum of S's squares)."""
    total = 0.0
    for i in range(_N):
        if p[_SQUARE_ROOT] != 0.0:
            row = 0.0  # a loop of constant length: compiled to a few instructions, not a vectorised loop
            for j in range(_N):
                row += state[_COV + _N * i + j] * state[_COV + _N * i + j]
            total += row
        else:
            total += state[_COV + (_N + 1) * i]
    return total


@register_jitable
def _take_fix(state, p, vn, ve, vd):
    """Book a new GPS velocity: the body-frame derivative v̇_b between consecutive fixes (eq. 5)."""
    if not (math.isfinite(vn) and math.isfinite(ve) and math.isfinite(vd)):
        return
    v_body = ned_to_body(state[0], state[1], state[2], state[3], vn, ve, vd)
    since = state[_SINCE_FIX]
    if not math.isnan(state[_V_BODY]) and since <= p[_GPS_TIMEOUT]:
        for i in range(3):
            state[_DV_BODY + i] = (v_body[i] - state[_V_BODY + i]) / since
        state[_FIX_INTERVAL] = since
    else:
        state[_DV_BODY] = math.nan
    state[_V_NED], state[_V_NED + 1], state[_V_NED + 2] = vn, ve, vd
    state[_V_BODY], state[_V_BODY + 1], state[_V_BODY + 2] = v_body
    state[_SINCE_FIX] = 0.0


@register_jitable
def _gravity_measurement(state, p, q_pred, gx, gy, gz, ax, ay, az, dt_s):
    """``(usable, down_x, down_y, down_z, σ², compensated)``: gravity's direction in the body, ``-(f -
    a_man)`` in g as measured (module docstring), the manoeuvre acceleration of eq. 5 removed while a GPS
    velocity is fresh; σ² of each component."""
    if not math.isnan(state[_DV_BODY]) and state[_SINCE_FIX] <= p[_GPS_TIMEOUT]:
        vx, vy, vz = ned_to_body(q_pred[0], q_pred[1], q_pred[2], q_pred[3], state[_V_NED], state[_V_NED + 1], state[_V_NED + 2])
        dx, dy, dz = state[_DV_BODY], state[_DV_BODY + 1], state[_DV_BODY + 2]
        mx, my, mz = dx + gy * vz - gz * vy, dy + gz * vx - gx * vz, dz + gx * vy - gy * vx  # eq. 5
        ax, ay, az = ax - mx / G, ay - my / G, az - mz / G
        state[_A_MAN] = math.sqrt(mx * mx + my * my + mz * mz)
        var = p[_ACC_VAR] + p[_VEL_VAR2] / (state[_FIX_INTERVAL] * dt_s * G * G)
        compensated = True
    else:
        state[_A_MAN] = 0.0
        var = p[_UNCOMPENSATED_VAR]
        compensated = False
    n2 = ax * ax + ay * ay + az * az
    if not (p[P_ACC_MIN2] <= n2 and n2 < math.inf):
        return False, 0.0, 0.0, 0.0, 0.0, compensated
    state[_ACC_PITCH], state[_ACC_ROLL] = acc_pitch_roll(ax, ay, az)
    return True, -ax, -ay, -az, var, compensated


@register_jitable
def _sigma_set(p):
    """The filter's set: ``(count, wm, wc, sqrt_wc, z)``."""
    count = int(p[_COUNT])
    return count, p[_WM : _WM + count], p[_WC : _WC + count], p[_SQRT_WC : _SQRT_WC + count - 1], sl.matrix_view(p, _Z, _N, count)


@register_jitable
def _predict(state, p, gx, gy, gz, dt_s):
    """The time update (seed 001 §2.2): ``(ok, x⁻, P⁻ or S⁻)``, views of the work space; not ok when a
    factorisation failed."""
    square_root = p[_SQUARE_ROOT] != 0.0
    count, wm, wc, sqrt_wc, z = _sigma_set(p)
    cov = _matrix(state, _COV, _N, _N)
    ok, factor = (True, cov) if square_root else sl.cholesky(cov, _matrix(state, _FACTOR, _N, _N))
    if not ok:
        return False, state[0:4], cov
    chi = sp.points(state[0:4], factor, z, _matrix(state, _CHI, count, _N))
    for k in range(count):
        chi[k, 0], chi[k, 1], chi[k, 2], chi[k, 3] = integrate_rate((chi[k, 0], chi[k, 1], chi[k, 2], chi[k, 3]), gx, gy, gz, dt_s)  # eq. 2
    q_noise = 0.5 * p[_GYRO_NOISE] * dt_s
    noise = state[_NOISE : _NOISE + _N]
    time_work = state[_TIME_WORK:_MEASUREMENT_WORK]
    if square_root:
        for i in range(_N):
            noise[i] = q_noise
        return sp.sqrt_time_update(chi, wm, wc, sqrt_wc, noise, time_work)
    for i in range(_N):
        noise[i] = q_noise * q_noise
    x, cov = sp.time_update(chi, wm, wc, noise, time_work)
    return True, x, cov


@register_jitable
def _correct(state, p, x, cov, gx, gy, gz, ax, ay, az, acc_ok, dt_s, heading_rad):
    """The measurement update (seed 001 §2.2) of the prediction ``x``, ``cov``: ``(ok, x, cov, measurement
    flags)``, views of the work space; not ok when a factorisation failed."""
    square_root = p[_SQUARE_ROOT] != 0.0
    count, wm, wc, sqrt_wc, z = _sigma_set(p)
    flags = 0
    r = _norm(x[0], x[1], x[2], x[3])
    q_pred = (x[0] / r, x[1] / r, x[2] / r, x[3] / r)
    # The measurements: gravity's three components (linear rows), then the heading (an angle)
    y, var = state[_Y : _Y + _M_MAX], state[_NOISE : _NOISE + _M_MAX]
    m = 0
    if acc_ok:
        usable, down_x, down_y, down_z, var_down, compensated = _gravity_measurement(state, p, q_pred, gx, gy, gz, ax, ay, az, dt_s)
        if usable:
            y[0], y[1], y[2] = down_x, down_y, down_z
            var[0], var[1], var[2] = var_down, var_down, var_down
            m = 3
            if compensated:
                flags |= GPS_COMPENSATED
    gravity = m
    if state[_YAW_KNOWN] != 0.0 and math.isfinite(heading_rad):
        y[m], var[m] = heading_rad, p[_HEADING_VAR]
        m += 1
        flags |= HEADING_USED
    if m == 0:
        return True, x, cov, flags
    ok, factor = (True, cov) if square_root else sl.cholesky(cov, _matrix(state, _FACTOR, _N, _N))
    if not ok:
        return False, x, cov, flags
    chi = sp.points(x, factor, z, _matrix(state, _CHI, count, _N))
    y_sigma = _matrix(state, _Y_SIGMA, m, count)
    for k in range(count):
        w, qx, qy, qz = chi[k, 0], chi[k, 1], chi[k, 2], chi[k, 3]
        if gravity:
            y_sigma[0, k], y_sigma[1, k], y_sigma[2, k] = down_in_body(w, qx, qy, qz)
        if m > gravity:
            y_sigma[gravity, k] = euler_angles(w, qx, qy, qz, True)[2]
    measurement_work = state[_MEASUREMENT_WORK:_STATE_END]
    if square_root:
        for i in range(m):
            var[i] = math.sqrt(var[i])
        ok, x, cov, innovation = sp.sqrt_measurement_update(x, cov, chi, y_sigma, y[:m], var[:m], wm, wc, sqrt_wc, measurement_work, gravity)
    else:
        ok, x, cov, innovation = sp.measurement_update(x, cov, chi, y_sigma, y[:m], var[:m], wm, wc, measurement_work, gravity)
    if ok:
        state[_INNOVATION] = math.sqrt(_dot(innovation))
        if gravity:
            # The lost test's low-pass of the gravity innovation (settings), over lost_time_s
            gain = dt_s / (p[_LOST_TIME] + dt_s)
            for i in range(3):
                state[_LOST + i] += (innovation[i] - state[_LOST + i]) * gain
    return ok, x, cov, flags


@register_jitable
def _with_yaw(w, qx, qy, qz, heading_rad):
    """``(w, qx, qy, qz)`` turned about NED z so that its yaw is ``heading_rad``."""
    half = 0.5 * wrap_pi(heading_rad - euler_angles(w, qx, qy, qz, True)[2])
    c, s = math.cos(half), math.sin(half)
    return c * w - s * qz, c * qx - s * qy, c * qy + s * qx, c * qz + s * w


@njit(cache=True)
def ukf_kernel(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz, vn, ve, vd, heading_rad):
    """One sample of ukf or sssrukf (``p[_SQUARE_ROOT]``): base.py's compiled kernels, with the GPS fix."""
    status, acc_ok, dt_s = guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
    # A start takes the initial covariance about the attitude from gravity. After a gap (REINITIALISED)
    # the covariance is kept: the tilt from gravity is what a tilt measurement would have said, and a
    # restarted covariance let the next noisy GPS-compensated measurements swing a still estimate by
    # 1.7° (test_intervals.py).
    if status & (INITIALISED | REINITIALISED) and state[_STARTING] != 0.0:
        _start(state, p)
    if status & REINITIALISED:
        # The craft may have turned any way during the gap: the yaw kept is as unknown as at the start, so
        # the next heading sets it outright (a 90° yaw innovation through the update tilted the estimate 60°)
        state[_YAW_KNOWN] = 0.0
    if not status & NO_UPDATE:
        state[_SINCE_FIX] += dt_s
        _take_fix(state, p, vn, ve, vd)
        state[_INNOVATION] = 0.0
        # The steps are called from here, not from one function calling the next: numba compiles each
        # caller with all its callees again (linked in), so a shallow call tree compiles faster.
        ok, x, cov = _predict(state, p, gx, gy, gz, dt_s)
        if ok:
            ok, x, cov, flags = _correct(state, p, x, cov, gx, gy, gz, ax, ay, az, acc_ok, dt_s, heading_rad)
            status |= flags
        status = _settle(state, p, ok, x, cov, status, gx, gy, gz, dt_s, heading_rad)
    state[_TRACE] = _trace(state, p)
    return status


@register_jitable
def _settle(state, p, ok, x, cov, status, gx, gy, gz, dt_s, heading_rad):
    """The estimate and covariance after a sample's filter step (``ok``: its ``x``, ``cov``; else restarted
    from the gyro's prediction): the filter restarted when lost, yaw set by the first heading."""
    if ok:
        w, qx, qy, qz = x[0], x[1], x[2], x[3]
        for i in range(_N):
            for j in range(_N):
                state[_COV + _N * i + j] = cov[i, j]
    else:
        w, qx, qy, qz = integrate_rate((state[0], state[1], state[2], state[3]), gx, gy, gz, dt_s)
        _initial_cov(state, p, w, qx, qy, qz)
        status |= COVARIANCE_RESET
    if _dot(state[_LOST : _LOST + 3]) > p[_LOST_INNOVATION] * p[_LOST_INNOVATION]:
        # Lost: the covariance no longer describes the error (settings): start it again
        r = _norm(w, qx, qy, qz)
        _initial_cov(state, p, w / r, qx / r, qy / r, qz / r)
        status |= COVARIANCE_RESET
        state[_LOST], state[_LOST + 1], state[_LOST + 2] = 0.0, 0.0, 0.0
    if state[_YAW_KNOWN] == 0.0 and math.isfinite(heading_rad):
        # The first heading sets yaw outright (module docstring)
        w, qx, qy, qz = _with_yaw(w, qx, qy, qz, heading_rad)
        state[_YAW_KNOWN] = 1.0
        status |= HEADING_USED
    norm = _norm(w, qx, qy, qz)
    state[0], state[1], state[2], state[3] = w / norm, qx / norm, qy / norm, qz / norm
    return status


@njit(cache=True)
def ukf_run(state, p, gyr, acc, dt, mag, gps, q_out, status_out, diag_out):
    state, p = unmanaged(state), unmanaged(p)
    for k in range(dt.shape[0]):  # base.CompiledEstimator
        record(state, k, ukf_kernel(state, p, *sample(gyr, acc, dt, mag, k), *sample_fix(gps, k)), status_out, q_out, diag_out)


class _GpsUkf(CompiledEstimator):
    """What both filters share; subclasses pick the sigma-point set and dense or square-root steps."""

    Diagnostics = GpsUkfDiagnostics
    kernel = staticmethod(ukf_kernel)
    run_kernel = staticmethod(ukf_run)
    gps_aided = True
    _square_root: ClassVar[bool]

    def _parameters(self):
        s = self.settings
        sigma = self._sigma_set(s)
        count = sigma.z.shape[1]
        std = 0.5 * s.initial_attitude_noise_rad  # a rotation θ moves q by θ/2
        room = _L_MAX - count
        return [
            float(self._square_root), float(count), s.gyro_noise_rad_s, s.acc_noise_g**2, 2.0 * s.gps_velocity_noise_m_s**2,
            s.uncompensated_acc_noise_g**2, s.heading_noise_rad**2, s.gps_timeout_s, std * std, (1e-3 * std) ** 2,
            s.lost_innovation_g, s.lost_time_s,
            *sigma.wm.tolist(), *[0.0] * room, *sigma.wc.tolist(), *[0.0] * room, *sigma.sqrt_wc.tolist(), *[0.0] * (room + 1),
            *sigma.z.reshape(-1).tolist(), *[0.0] * (_N * room),
        ]  # fmt: skip

    def _initial_state(self):
        # the diagnostics, a covariance filled in by reset, starting, yaw unknown, no fix, not lost
        return [0.0, 0.0, 0.0, 0.0, 0.0, *[0.0] * (_N * _N), 1.0, 0.0, math.inf, math.inf, *[math.nan] * 9, *[0.0] * 3, *[0.0] * (_STATE_END - _FACTOR)]

    def reset(self, q0=None) -> None:
        super().reset(q0)
        # the kernel reads the sigma set as arrays, also where it runs interpreted
        self._params = np.asarray(self._params, dtype=self._dtype)
        q = (1.0, 0.0, 0.0, 0.0) if q0 is None else quaternion.normalise(q0).tolist()
        _initial_cov(self._state, self._params, *q)
        self._state[_STARTING] = float(q0 is None)  # a given q0 is the start
        self._state[_TRACE] = _trace(self._state, self._params)


class Ukf(_GpsUkf):
    """Standard UKF: 2n + 1 = 9 symmetric sigma points, full covariance, Cholesky twice a sample."""

    name = "ukf"
    Settings = UkfSettings
    _square_root = False

    @staticmethod
    def _sigma_set(s):
        return sp.symmetric(_N, s.ut_alpha, s.ut_beta, s.ut_kappa)


class Sssrukf(_GpsUkf):
    """Seed 001's SSSRUKF: square-root UKF, additive noise, n + 2 = 6 spherical simplex sigma points."""

    name = "sssrukf"
    Settings = SssrukfSettings
    _square_root = True

    @staticmethod
    def _sigma_set(s):
        return sp.spherical_simplex(_N, s.simplex_w0, s.ut_alpha, s.ut_beta)

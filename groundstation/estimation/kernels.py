"""Compiled batch runs of ``ahf``, ``hf`` and ``ecf``: whole arrays in, quaternions and diagnostics out.

The same arithmetic as each estimator's ``step`` (``base.Estimator.step`` for the input guards,
``Ahf._update`` and ``Ecf._update`` for the corrections), in the same order of operations, written
once over plain floats so that numba compiles it (``@njit(cache=True)``: compiled on the first call
on a machine, then loaded from ``__pycache__``). Without numba the same functions run as plain
Python, so numba is an optional speed-up, never a requirement (the ``fast`` extra installs it).

Why numba: the estimators are scalar recurrences (each sample needs the previous state), which numpy
cannot vectorise; numba compiles the existing Python arithmetic nearly unchanged, keeps one source
for the compiled and the interpreted path, and needs no compiler on the user's machine (Cython or a
C extension would, or a wheel per platform). Its cost is the compile on first use, measured in
``bench/bench_kernels.py``.

Inputs: ``gyr_rad_s`` (N, 3), ``acc_g`` (N, 3), ``dt_s`` (N,), float64, body FRD axes, as ``run``
takes them; the run starts from a fresh estimator (``reset()`` without ``q0``). Outputs: ``q`` (N, 4)
w-first body -> NED, and the diagnostics as ``run`` returns them (a dict of (N,) arrays, ``status``
int64). float64 only: the float32 (onboard) mode of ``ahf`` stays on ``step``.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation.estimation.base import ACC_SKIPPED, GYRO_OVERRANGE, HELD, INITIALISED, REINITIALISED, WAITING

try:
    from numba import njit
except ImportError:  # numba is optional: the same functions, interpreted

    def njit(**_options):
        return lambda function: function


@njit(cache=True)
def _attitude_from_acc(ax, ay, az, yaw_rad, q):
    """``Estimator._attitude_from_acc`` into ``q``: tilt.acc_pitch_roll, then quaternion.from_euler_zyx."""
    pitch = math.atan2(ax, math.sqrt(ay * ay + az * az))
    roll = math.atan2(-ay, -az)
    hy, hp, hr = yaw_rad / 2.0, pitch / 2.0, roll / 2.0
    cy, sy, cp, sp, cr, sr = math.cos(hy), math.sin(hy), math.cos(hp), math.sin(hp), math.cos(hr), math.sin(hr)
    q[0] = cy * cp * cr + sy * sp * sr
    q[1] = cy * cp * sr - sy * sp * cr
    q[2] = cy * sp * cr + sy * cp * sr
    q[3] = sy * cp * cr - cy * sp * sr


@njit(cache=True)
def _guard(gx, gy, gz, ax, ay, az, dt_s, q, waiting, acc_min2, acc_max2, max_gap_s):
    """``Estimator.step`` before ``_update``: returns ``(update, status, acc_ok, waiting)``; ``q`` is
    changed in place when the sample initialises or re-initialises the attitude."""
    n2 = ax * ax + ay * ay + az * az
    acc_ok = acc_min2 <= n2 and n2 <= acc_max2  # NaN fails both, Inf the second
    status = 0
    if waiting:
        if not acc_ok:
            return False, WAITING, acc_ok, True
        _attitude_from_acc(ax, ay, az, 0.0, q)
        waiting = False
        status = INITIALISED
    total = gx + gy + gz + dt_s
    if not dt_s > 0.0 or total - total != 0.0:  # dt <= 0, or a NaN/Inf in gyro or dt
        return False, status | HELD, acc_ok, waiting
    if dt_s > max_gap_s:
        if not acc_ok:
            return False, status | HELD, acc_ok, waiting
        yaw = math.atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]))  # quaternion.to_euler_zyx
        _attitude_from_acc(ax, ay, az, yaw, q)
        return False, status | REINITIALISED, acc_ok, waiting
    if not acc_ok:
        status |= ACC_SKIPPED
    return True, status, acc_ok, waiting


@njit(cache=True)
def _store_normalised(q, q1, q2, q3, q4):
    r = (q1 * q1 + q2 * q2 + q3 * q3 + q4 * q4) ** -0.5
    q[0], q[1], q[2], q[3] = q1 * r, q2 * r, q3 * r, q4 * r


@njit(cache=True)
def ahf_kernel(gyr, acc, dt, acc_min2, acc_max2, max_gap_s, adaptive, lam_max, lam_min, lowpass, gain, overrange, overrange_on):
    """Ahf (``adaptive``) or Hf (λ fixed at ``lam_max`` = β): ``Ahf._update`` per sample.

    ``gain`` is ``(1 - lowpass) * error_gain``; returns q (N, 4), status, λ, e_a, gravity_error."""
    n = gyr.shape[0]
    q_out = np.empty((n, 4))
    status_out = np.empty(n, dtype=np.int64)
    lam_out, e_a_out, err_out = np.empty(n), np.empty(n), np.empty(n)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    waiting = True
    e_a, lam, err = 0.0, lam_max, 0.0
    for k in range(n):
        gx, gy, gz = gyr[k, 0], gyr[k, 1], gyr[k, 2]
        ax, ay, az = acc[k, 0], acc[k, 1], acc[k, 2]
        dt_s = dt[k]
        update, status, acc_ok, waiting = _guard(gx, gy, gz, ax, ay, az, dt_s, q, waiting, acc_min2, acc_max2, max_gap_s)
        if update:
            q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
            d1 = 0.5 * (-q2 * gx - q3 * gy - q4 * gz)
            d2 = 0.5 * (q1 * gx + q3 * gz - q4 * gy)
            d3 = 0.5 * (q1 * gy - q2 * gz + q4 * gx)
            d4 = 0.5 * (q1 * gz + q2 * gy - q3 * gx)
            if acc_ok:
                r = -((ax * ax + ay * ay + az * az) ** -0.5)
                ax, ay, az = ax * r, ay * r, az * r
                vx = 2.0 * (q2 * q4 - q1 * q3)
                vy = 2.0 * (q1 * q2 + q3 * q4)
                vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4
                fx, fy, fz = vx - ax, vy - ay, vz - az
                s1 = -2.0 * q3 * fx + 2.0 * q2 * fy
                s2 = 2.0 * q4 * fx + 2.0 * q1 * fy - 4.0 * q2 * fz
                s3 = -2.0 * q1 * fx + 2.0 * q4 * fy - 4.0 * q3 * fz
                s4 = 2.0 * q2 * fx + 2.0 * q3 * fy
                err = abs(vy * az - vz * ay) + abs(vz * ax - vx * az) + abs(vx * ay - vy * ax)
                lam = lam_max
                if adaptive:
                    e_a = lowpass * e_a + gain * err
                    lam = lam - e_a
                    if lam < lam_min:
                        lam = lam_min
                    elif lam > lam_max:
                        lam = lam_max
                    if overrange_on and (abs(gx) >= overrange or abs(gy) >= overrange or abs(gz) >= overrange):
                        lam = lam_max
                        status |= GYRO_OVERRANGE
                n2 = s1 * s1 + s2 * s2 + s3 * s3 + s4 * s4
                if n2 > 0.0:
                    g = lam * n2**-0.5
                    d1, d2, d3, d4 = d1 - g * s1, d2 - g * s2, d3 - g * s3, d4 - g * s4
            _store_normalised(q, q1 + d1 * dt_s, q2 + d2 * dt_s, q3 + d3 * dt_s, q4 + d4 * dt_s)
        q_out[k] = q  # the identity while waiting
        status_out[k], lam_out[k], e_a_out[k], err_out[k] = status, lam, e_a, err
    return q_out, status_out, lam_out, e_a_out, err_out


@njit(cache=True)
def ecf_kernel(gyr, acc, dt, acc_min2, acc_max2, max_gap_s, kp, ki):
    """Ecf: ``Ecf._update`` per sample; returns q (N, 4), status, bias x, y, z (rad/s), gravity_error."""
    n = gyr.shape[0]
    q_out = np.empty((n, 4))
    status_out = np.empty(n, dtype=np.int64)
    bias_out = np.empty((n, 3))
    err_out = np.empty(n)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    waiting = True
    bx, by, bz, err = 0.0, 0.0, 0.0, 0.0
    for k in range(n):
        gx, gy, gz = gyr[k, 0], gyr[k, 1], gyr[k, 2]
        ax, ay, az = acc[k, 0], acc[k, 1], acc[k, 2]
        dt_s = dt[k]
        update, status, acc_ok, waiting = _guard(gx, gy, gz, ax, ay, az, dt_s, q, waiting, acc_min2, acc_max2, max_gap_s)
        if update:
            q1, q2, q3, q4 = q[0], q[1], q[2], q[3]
            if acc_ok:
                r = -((ax * ax + ay * ay + az * az) ** -0.5)
                ax, ay, az = ax * r, ay * r, az * r
                vx = 2.0 * (q2 * q4 - q1 * q3)
                vy = 2.0 * (q1 * q2 + q3 * q4)
                vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4
                ex, ey, ez = ay * vz - az * vy, az * vx - ax * vz, ax * vy - ay * vx
                err = (ex * ex + ey * ey + ez * ez) ** 0.5
                kidt = ki * dt_s
                bx, by, bz = bx - kidt * ex, by - kidt * ey, bz - kidt * ez
                gx, gy, gz = gx + kp * ex, gy + kp * ey, gz + kp * ez
            # base.integrate_rate
            wx, wy, wz = gx - bx, gy - by, gz - bz
            h = 0.5 * dt_s
            _store_normalised(
                q,
                q1 - h * (q2 * wx + q3 * wy + q4 * wz),
                q2 + h * (q1 * wx + q3 * wz - q4 * wy),
                q3 + h * (q1 * wy - q2 * wz + q4 * wx),
                q4 + h * (q1 * wz + q2 * wy - q3 * wx),
            )
        q_out[k] = q  # the identity while waiting
        status_out[k], err_out[k] = status, err
        bias_out[k, 0], bias_out[k, 1], bias_out[k, 2] = bx, by, bz
    return q_out, status_out, bias_out, err_out


def _inputs(gyr_rad_s, acc_g, dt_s):
    gyr = np.ascontiguousarray(gyr_rad_s, dtype=float).reshape(-1, 3)
    acc = np.ascontiguousarray(acc_g, dtype=float).reshape(-1, 3)
    if len(acc) != len(gyr):
        raise ValueError(f"gyr_rad_s has {len(gyr)} rows but acc_g has {len(acc)}")
    dt = np.ascontiguousarray(np.broadcast_to(np.asarray(dt_s, dtype=float), (len(gyr),)))
    return gyr, acc, dt


def _guards(settings) -> tuple[float, float, float]:
    return settings.acc_min_g * settings.acc_min_g, settings.acc_max_g * settings.acc_max_g, float(settings.max_gap_s)


def run_ahf(settings, gyr_rad_s, acc_g, dt_s):
    """``Ahf(settings).run`` (``AhfSettings``) or ``Hf(settings).run`` (``HfSettings``) from a fresh start."""
    adaptive = hasattr(settings, "lambda_max")
    if adaptive:
        lam = (float(settings.lambda_max), float(settings.lambda_min), float(settings.lowpass))
        gain, overrange = (1.0 - settings.lowpass) * settings.error_gain, float(settings.gyro_overrange_rad_s)
    else:
        lam, gain, overrange = (float(settings.beta), 0.0, 0.0), 0.0, math.inf
    q, status, lam_used, e_a, err = ahf_kernel(
        *_inputs(gyr_rad_s, acc_g, dt_s), *_guards(settings), adaptive, *lam, gain, overrange, overrange != math.inf
    )
    return q, {"status": status, "lam": lam_used, "e_a": e_a, "gravity_error": err}


def run_ecf(settings, gyr_rad_s, acc_g, dt_s):
    """``Ecf(settings).run`` from a fresh start."""
    q, status, bias, err = ecf_kernel(*_inputs(gyr_rad_s, acc_g, dt_s), *_guards(settings), float(settings.kp), float(settings.ki))
    return q, {"status": status, "bias_x_rad_s": bias[:, 0], "bias_y_rad_s": bias[:, 1], "bias_z_rad_s": bias[:, 2], "gravity_error": err}

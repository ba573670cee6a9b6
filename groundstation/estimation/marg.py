"""HFM and ECFM: Madgwick's and Mahony's filters with the magnetometer (MARG), so yaw is observable.

Both reuse their IMU filter (``ahf.Hf``, ``ecf.Ecf``) through one hook each; on a sample without a usable
magnetometer reading (None, NaN, zero) or without a usable accelerometer they are exactly the IMU filter.

The earth field is not needed: as in Madgwick (2010, §3.4 eq. 45-46) and Mahony et al. (2008, §5), the
measured field ``m̂ = m/‖m‖`` is rotated into the earth frame with the current estimate, ``h = R(q) m̂``,
and its horizontal part is taken to point north: the reference is ``b = (‖h_n,e‖, 0, h_d)`` in NED.
Yaw is therefore *magnetic* heading (add the declination for true north), and the dip never enters.
The field must be free of hard and soft iron first (``magcal``).

- HFM (Madgwick MARG, β fixed = HF's ``beta``, rad/s): the objective gets three rows
  ``f_b = Rᵀ(q) b - m̂`` (Madgwick eq. 29, 31), the Jacobian three more (eq. 30, 32), and the gradient
  step of seed 000 eq. 12, 18 uses ``∇f = J_gᵀ f_g + J_bᵀ f_b``, normalised as before.
- ECFM (Mahony ECF with the magnetometer, seed 002 / digest §4 ``e = a × v + m × w``): the estimated
  field direction on the body axes ``w = Rᵀ(q) b`` adds ``m̂ × w`` to the error that drives the PI
  correction (Mahony eq. 48a).

Frames: the accelerometer enters as in ahf.py (the measured down direction ``-acc/‖acc‖``), the
magnetometer as it is (µT on body FRD axes; only its direction matters), so the earth frame is NED.
ahrs's Madgwick uses the same ``b``; ahrs's Mahony puts the field on earth +y (tests/estimation/test_marg.py
turns its frame by 90° about z to compare).

Initial yaw: when the attitude is set from gravity (the first usable sample after ``reset()`` without
``q0``, and after a gap longer than ``max_gap_s``) and that sample has a magnetometer reading, yaw is set to
the tilt-compensated compass heading (``compass.heading_rad``) instead of 0 or the stale yaw, so the
filter does not spend tens of seconds turning to north at β or Kp. Without a reading then, the
magnetometer term turns yaw at the filter's own rate. ``reset(q0)`` starts from ``q0`` as given.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation import quaternion
from groundstation.estimation.ahf import Hf
from groundstation.estimation.base import Estimator
from groundstation.estimation.compass import heading_rad
from groundstation.estimation.ecf import Ecf


def _unit_field(mag):
    """m̂ as three floats, or None when the reading is missing, non-finite or zero."""
    if mag is None:
        return None
    mx, my, mz = mag
    n2 = mx * mx + my * my + mz * mz
    if not 0.0 < n2 < math.inf:  # NaN fails, Inf and 0 excluded
        return None
    r = n2**-0.5
    return mx * r, my * r, mz * r


def _earth_reference(q1, q2, q3, q4, mx, my, mz):
    """``b = (bx, 0, bz)``: the measured field turned into NED, its horizontal part onto north
    (Madgwick eq. 45-46): ``h = R(q) m̂``, ``bx = ‖(h_n, h_e)‖``, ``bz = h_d``."""
    hx = (1.0 - 2.0 * (q3 * q3 + q4 * q4)) * mx + 2.0 * (q2 * q3 - q1 * q4) * my + 2.0 * (q2 * q4 + q1 * q3) * mz
    hy = 2.0 * (q2 * q3 + q1 * q4) * mx + (1.0 - 2.0 * (q2 * q2 + q4 * q4)) * my + 2.0 * (q3 * q4 - q1 * q2) * mz
    hz = 2.0 * (q2 * q4 - q1 * q3) * mx + 2.0 * (q3 * q4 + q1 * q2) * my + (1.0 - 2.0 * (q2 * q2 + q3 * q3)) * mz
    return (hx * hx + hy * hy) ** 0.5, hz


class _CompassYaw:
    """Yaw from the compass whenever the attitude is (re)set from gravity on a sample with a reading."""

    def _attitude_from_acc(self, ax, ay, az, yaw_rad):
        q = Estimator._attitude_from_acc(ax, ay, az, yaw_rad)
        if _unit_field(self._mag) is None:
            return q
        yaw = float(heading_rad(np.array(q), np.array(self._mag, dtype=float)))
        _, pitch, roll = quaternion.to_euler_zyx(np.array(q))
        return tuple(quaternion.from_euler_zyx(yaw, pitch, roll).tolist())


class Hfm(_CompassYaw, Hf):
    """Madgwick's MARG filter: HF (β fixed) plus the magnetometer's gradient (module docstring)."""

    name = "hfm"
    marg = True

    def _mag_gradient(self, q1, q2, q3, q4, s1, s2, s3, s4):
        m = _unit_field(self._mag)
        if m is None:
            return s1, s2, s3, s4
        mx, my, mz = m
        bx, bz = _earth_reference(q1, q2, q3, q4, mx, my, mz)
        # (Madgwick eq. 31) f_b = Rᵀ(q) b - m̂
        f4 = 2.0 * bx * (0.5 - q3 * q3 - q4 * q4) + 2.0 * bz * (q2 * q4 - q1 * q3) - mx
        f5 = 2.0 * bx * (q2 * q3 - q1 * q4) + 2.0 * bz * (q1 * q2 + q3 * q4) - my
        f6 = 2.0 * bx * (q1 * q3 + q2 * q4) + 2.0 * bz * (0.5 - q2 * q2 - q3 * q3) - mz
        # (Madgwick eq. 32, 34) ∇f += J_bᵀ f_b
        s1 += -2.0 * bz * q3 * f4 + (-2.0 * bx * q4 + 2.0 * bz * q2) * f5 + 2.0 * bx * q3 * f6
        s2 += 2.0 * bz * q4 * f4 + (2.0 * bx * q3 + 2.0 * bz * q1) * f5 + (2.0 * bx * q4 - 4.0 * bz * q2) * f6
        s3 += (-4.0 * bx * q3 - 2.0 * bz * q1) * f4 + (2.0 * bx * q2 + 2.0 * bz * q4) * f5 + (2.0 * bx * q1 - 4.0 * bz * q3) * f6
        s4 += (-4.0 * bx * q4 + 2.0 * bz * q2) * f4 + (-2.0 * bx * q1 + 2.0 * bz * q3) * f5 + 2.0 * bx * q2 * f6
        return s1, s2, s3, s4


class Ecfm(_CompassYaw, Ecf):
    """Mahony's ECF with the magnetometer error term ``e += m̂ × w`` (module docstring)."""

    name = "ecfm"
    marg = True

    def _mag_error(self, q1, q2, q3, q4, ex, ey, ez):
        m = _unit_field(self._mag)
        if m is None:
            return ex, ey, ez
        mx, my, mz = m
        bx, bz = _earth_reference(q1, q2, q3, q4, mx, my, mz)
        # w = Rᵀ(q) b: the estimated field direction on the body axes
        wx = bx * (1.0 - 2.0 * (q3 * q3 + q4 * q4)) + bz * 2.0 * (q2 * q4 - q1 * q3)
        wy = bx * 2.0 * (q2 * q3 - q1 * q4) + bz * 2.0 * (q1 * q2 + q3 * q4)
        wz = bx * 2.0 * (q2 * q4 + q1 * q3) + bz * (1.0 - 2.0 * (q2 * q2 + q3 * q3))
        # (Mahony eq. 48a) e += m̂ × w
        return ex + my * wz - mz * wy, ey + mz * wx - mx * wz, ez + mx * wy - my * wx

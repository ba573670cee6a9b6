"""HFM and ECFM: Madgwick's and Mahony's filters with the magnetometer (MARG), so yaw is observable.

Both are their IMU filter (``ahf.Hf``, ``ecf.Ecf``), whose compiled kernel adds the magnetometer's term when
``uses_magnetometer`` is set (``ahf._field_gradient``, ``ecf._field_error``); on a sample without a usable
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
the tilt-compensated compass heading (``compass.level_heading_rad``, in base.py's guard) instead of 0 or the stale yaw, so the
filter does not spend tens of seconds turning to north at β or Kp. Without a reading then, the
magnetometer term turns yaw at the filter's own rate. ``reset(q0)`` starts from ``q0`` as given.
"""

from __future__ import annotations

from groundstation.estimation.ahf import Hf
from groundstation.estimation.ecf import Ecf


class Hfm(Hf):
    """Madgwick's MARG filter: HF (β fixed) plus the magnetometer's gradient (module docstring; ahf.py)."""

    name = "hfm"
    uses_magnetometer = True


class Ecfm(Ecf):
    """Mahony's ECF with the magnetometer error term ``e += m̂ × w`` (module docstring; ecf.py)."""

    name = "ecfm"
    uses_magnetometer = True

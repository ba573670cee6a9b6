"""HFM and ECFM: Madgwick's and Mahony's filters with the magnetometer (MARG), so yaw is observable.

Both are their IMU filter (``ahf.Hf``, ``ecf.Ecf``), whose compiled kernel adds the magnetometer's term when
``uses_magnetometer`` is set (``ahf._field_gradient``, ``ecf._field_error``); on a sample without a usable
magnetometer reading (None, NaN, zero, or one ``base.field_screen`` rejects) or without a usable
accelerometer they are exactly the IMU filter.

The earth field is not needed: as in Madgwick (2010, §3.4 eq. 45-46) and Mahony et al. (2008, §5), the
measured field ``m̂ = m/‖m‖`` is rotated into the earth frame with the current estimate, ``h = R(q) m̂``,
and its horizontal part is taken to point north: the reference is ``b = (‖h_n,e‖, 0, h_d)`` in NED.
Yaw is therefore *magnetic* heading (add the declination for true north). The field must be free of hard
and soft iron first (``magcal``).

The magnetometer corrects heading only (issue 33): the published terms below also tilt the estimate
toward wherever the field says down is, so a magnet 1 cm from the sensor took ECFM's inclination on a
BROAD trial from ECF's 1.34° RMSE to 76°. Here each term keeps only its turn about the vertical
(``tilt.about_vertical``, ``about_vertical_q``), so pitch and roll are the IMU filter's, and a reading
whose norm or dip is off the learnt field is rejected (``base.field_screen``, VQF's rule; ``MAG_REJECTED``
in the status). The cost: heading is as good as the tilt it is levelled with (a tilt error turns the compass
heading by up to tan(dip) times it).

- HFM (Madgwick MARG, β fixed = HF's ``beta``, rad/s): the objective's three field rows
  ``f_b = Rᵀ(q) b - m̂`` (Madgwick eq. 29, 31) and their Jacobian (eq. 30, 32) give the gradient
  ``J_bᵀ f_b``; its part about the vertical is a second step of its own, ``q̇ -= β ∇f_b/‖∇f + ∇f_b‖``, beside
  seed 000 eq. 12, 18's gravity step ``q̇ -= β ∇f/‖∇f‖`` (Madgwick sums the two before normalising, so a
  field reading would change how fast gravity corrects tilt). The field's step keeps Madgwick's share of
  the sum (``∇f`` turns about a horizontal axis, ``∇f_b`` about the vertical: orthogonal, so
  ``‖∇f + ∇f_b‖² = ‖∇f‖² + ‖∇f_b‖²``), small while the heading error is small beside the tilt's. Normalised
  alone it turned heading at β whatever the error and followed each compass heading its tilt error
  skewed (× tan dip): BROAD trial 16, 6.75° heading RMSE; 2.77° so (issue 33).
- ECFM (Mahony ECF with the magnetometer, seed 002 / digest §4 ``e = a × v + m × w``): the estimated
  field direction on the body axes ``w = Rᵀ(q) b`` adds the part of ``m̂ × w`` about the vertical to the
  error that drives the PI correction (Mahony eq. 48a).

Frames: the accelerometer enters as in ahf.py (the measured down direction ``-acc/‖acc‖``), the
magnetometer as it is (µT on body FRD axes; only its direction matters), so the earth frame is NED.
ahrs's Madgwick uses the same ``b`` (ahrs's Mahony puts the field on earth +y).

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
    """Madgwick's MARG filter: HF (β fixed) plus the magnetometer's gradient about the vertical (module docstring; ahf.py)."""

    name = "hfm"
    uses_magnetometer = True


class Ecfm(Ecf):
    """Mahony's ECF with the magnetometer error term ``e += m̂ × w`` about the vertical (module docstring; ecf.py)."""

    name = "ecfm"
    uses_magnetometer = True

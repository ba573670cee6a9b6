"""Accuracy against truth: BROAD's inclination and heading errors, and running estimators over a dataset trial.

Inclination error (Laidig et al., BROAD, 2021): the angle between the estimated and the true gravity
direction, both expressed in the sensor frame, so heading does not matter. Estimates are body -> NED,
so the estimated *down* direction in the sensor frame is ``R(q)ᵀ e_z``; dataset truth is IMU -> ENU,
whose ``R(q)ᵀ e_z`` is *up*. The RMSE is over the ``moving`` samples that have truth, in degrees.

Heading error (BROAD's for filters with a magnetometer; ../shared/datasets/README.md): the truth is
turned into NED (ENU -> NED is the half turn about the north-east bisector), and the rotation between
estimate and truth, ``q_e = q_est ⊗ q_true⁻¹`` (earth frame), is split into a turn about the vertical
after a turn about a horizontal axis, ``q_e = q_z(ψ) ⊗ q_h``; then ``ψ = 2 atan2(q_e,z, q_e,w)`` (q_h has
no z part, so the product's z/w is tan ψ/2), positive clockwise seen from above as every yaw here. The truth's x axis is not magnetic north, so one constant offset per trial, the circular mean
of ψ over the ``moving`` samples that have truth (the scored ones, as the datasets README says), is removed first; turning the estimate about the vertical by that
offset moves ψ by exactly the offset. RMSE over the ``moving`` samples that have truth, in degrees.
Scored for the estimators that use a magnetometer (``Estimator.uses_magnetometer``) on data that has one;
the heading of the others is the gyro's and drifts by design.
"""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np

from groundstation import quaternion
from groundstation.estimation import ESTIMATORS, create
from groundstation.units import STANDARD_GRAVITY_M_S2

_EARTH_Z = np.array([0.0, 0.0, 1.0])
_H = np.sqrt(0.5)
_TO_NED = {"ENU": np.array([0.0, _H, _H, 0.0]), "NED": np.array([1.0, 0.0, 0.0, 0.0])}  # the truth's earth frame -> NED


def inclination_error_rad(q_est, q_true, truth_frame: str = "ENU") -> np.ndarray:
    """Per-sample angle (rad) between estimated (body -> NED) and true gravity, in the sensor frame.

    ``truth_frame`` says where the truth's earth z points: "ENU" (up; the dataset CSVs) or "NED" (down).
    NaN where the truth is NaN.
    """
    down_est = quaternion.rotate(quaternion.conjugate(q_est), _EARTH_Z)
    z_true = quaternion.rotate(quaternion.conjugate(q_true), _EARTH_Z)
    down_true = -z_true if truth_frame == "ENU" else z_true
    cross = np.linalg.norm(np.cross(down_est, down_true), axis=-1)
    return np.arctan2(cross, np.sum(down_est * down_true, axis=-1))


def truth_in_ned(q_true, truth_frame: str = "ENU") -> np.ndarray:
    """The truth (body -> ``truth_frame``) as body -> NED, comparable with the estimates angle for angle."""
    return quaternion.multiply(_TO_NED[truth_frame], q_true)


def heading_error_rad(q_est, q_true, truth_frame: str = "ENU", mask=None) -> np.ndarray:
    """Per-sample heading error (rad, in (-π, π]) of estimates (body -> NED) against the truth, after
    removing the trial's constant offset, the circular mean over the samples in ``mask`` (the scored
    ones; all when None) that have truth (module docstring); NaN where the truth is NaN."""
    q_e = quaternion.multiply(q_est, quaternion.conjugate(truth_in_ned(q_true, truth_frame)))
    psi = 2.0 * np.arctan2(q_e[..., 3], q_e[..., 0])
    known = np.isfinite(psi) if mask is None else np.isfinite(psi) & np.asarray(mask, dtype=bool)
    if not known.any():
        return psi
    offset = np.arctan2(np.mean(np.sin(psi[known])), np.mean(np.cos(psi[known])))
    return np.angle(np.exp(1j * (psi - offset)))


def score(error_rad, mask=None, prefix: str = "incl") -> dict[str, float]:
    """``{"incl_rmse_deg", "incl_max_deg"}`` over the samples in ``mask`` that have truth (``prefix``
    "heading": ``heading_rmse_deg``, ``heading_max_deg``, of the absolute error)."""
    error = np.abs(np.asarray(error_rad, dtype=float))
    keep = np.isfinite(error) if mask is None else np.isfinite(error) & np.asarray(mask, dtype=bool)
    if not keep.any():
        raise ValueError("no samples with truth to score")
    e = np.degrees(error[keep])
    return {f"{prefix}_rmse_deg": float(np.sqrt(np.mean(e * e))), f"{prefix}_max_deg": float(e.max())}


def uses_magnetometer(name: str) -> bool:
    """True for an estimator whose heading comes from the magnetometer when there is one."""
    cls = ESTIMATORS.get(name)
    return bool(cls and cls.uses_magnetometer)


def gives_heading(name: str) -> bool:
    """True for an estimator whose yaw has a reference (the magnetometer, or the GPS velocity it needs); the
    others' yaw is the gyro's integral from an arbitrary start, no heading."""
    return uses_magnetometer(name) or (name in ESTIMATORS and "gps" in ESTIMATORS.about(name).needs)


def scores(q_est, q_true, mask, truth_frame: str = "ENU", heading: bool = False) -> dict[str, float]:
    """Inclination figures (``score``), and the heading's too when ``heading``."""
    figures = score(inclination_error_rad(q_est, q_true, truth_frame), mask)
    if heading:
        figures |= score(heading_error_rad(q_est, q_true, truth_frame, mask), mask, "heading")
    return figures


def sample_periods_s(time_s) -> np.ndarray:
    """dt for each sample: the gap since the previous one; the first gets the median gap."""
    time_s = np.asarray(time_s, dtype=float)
    gaps = np.diff(time_s)
    first = np.median(gaps) if len(gaps) else 0.0
    return np.concatenate([[first], gaps])


def resampled(trial, rate_hz: float):
    """The trial at ``rate_hz`` (a board's rate): the sensors through scipy's polyphase resampler (its
    anti-aliasing low-pass, as a board's sensor filter, fed the edge values beyond the ends: zeros made
    the first samples ring from 0), the truth interpolated between its two nearest
    samples (normalised linear, NaN if either is NaN), ``moving`` from the nearest sample. The rate ratio
    must be a ratio of small integers (BROAD's 2000/7 Hz to 100 Hz: 7/20)."""
    period_s = float(np.median(np.diff(trial.time_s)))
    ratio = Fraction(rate_hz * period_s).limit_denominator(100)
    if abs(ratio - rate_hz * period_s) > 1e-3 * rate_hz * period_s:
        raise ValueError(f"{rate_hz:g} Hz is not a small rational multiple of the trial's {1.0 / period_s:g} Hz")
    up, down = ratio.numerator, ratio.denominator

    from scipy.signal import resample_poly  # here: scipy.signal costs the app's start a second (bench/bench_first_frame.py)

    def sensor(values):  # padded with the edge values: the sensor was on before and after, not at zero
        return None if values is None else resample_poly(values, up, down, axis=0, padtype="edge")

    gyr = sensor(trial.gyr_rad_s)
    position = np.arange(len(gyr)) * down / up  # in input samples
    true_q = None
    if trial.true_q is not None:
        i0 = np.minimum(position.astype(int), len(trial.time_s) - 2)
        a = (position - i0)[:, None]
        q0, q1 = trial.true_q[i0], trial.true_q[i0 + 1]
        q1 = q1 * np.where(np.sum(q0 * q1, axis=1, keepdims=True) < 0.0, -1.0, 1.0)  # the same hemisphere
        true_q = quaternion.normalise((1.0 - a) * q0 + a * q1)
    nearest = np.minimum(np.rint(position).astype(int), len(trial.time_s) - 1)
    return dataclasses.replace(
        trial, time_s=trial.time_s[0] + position * period_s, gyr_rad_s=gyr, acc_m_s2=sensor(trial.acc_m_s2),
        mag_uT=sensor(trial.mag_uT), true_q=true_q, moving=None if trial.moving is None else trial.moving[nearest],
    )


def run_on_trial(trial, names, overrides=None) -> dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]:
    """Each named estimator (fresh, defaults + ``overrides[name]``) run over a trial with its gyro,
    accelerometer and magnetometer (when the trial has one; those that do not use it ignore it):
    name -> (q, diag).

    The IMU axes are taken as the body axes (identity mounting): neither error depends on how the
    sensor is mounted. ValueError for an unknown name or setting.
    """
    overrides = overrides or {}
    acc_g = trial.acc_m_s2 / STANDARD_GRAVITY_M_S2
    dt_s = sample_periods_s(trial.time_s)
    return {name: create(name, overrides.get(name)).run(trial.gyr_rad_s, acc_g, dt_s, trial.mag_uT) for name in dict.fromkeys(names)}


def evaluate_trial(trial, names, overrides=None) -> dict[str, dict[str, float]]:
    """Run each named estimator over a trial (``run_on_trial``) and score it against the truth: the
    inclination, and the heading of those that use the magnetometer when the trial has one."""
    if trial.true_q is None:
        raise ValueError("the file has no truth columns (true_qw ... true_qz) to evaluate against")
    mask = trial.moving if trial.moving is not None else np.ones(len(trial), dtype=bool)
    has_mag = trial.mag_uT is not None
    return {name: scores(q, trial.true_q, mask, heading=has_mag and uses_magnetometer(name)) for name, (q, _) in run_on_trial(trial, names, overrides).items()}

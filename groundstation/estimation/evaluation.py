"""Accuracy against truth: BROAD's inclination error, and running estimators over a dataset trial.

Inclination error (Laidig et al., BROAD, 2021): the angle between the estimated and the true gravity
direction, both expressed in the sensor frame, so heading does not matter. Estimates are body -> NED,
so the estimated *down* direction in the sensor frame is ``R(q)ᵀ e_z``; dataset truth is IMU -> ENU,
whose ``R(q)ᵀ e_z`` is *up*. The RMSE is over the ``moving`` samples that have truth, in degrees.
"""

from __future__ import annotations

import numpy as np

from groundstation import quaternion
from groundstation.estimation import create
from groundstation.units import STANDARD_GRAVITY_M_S2

_EARTH_Z = np.array([0.0, 0.0, 1.0])


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


def score(error_rad, mask=None) -> dict[str, float]:
    """``{"incl_rmse_deg", "incl_max_deg"}`` over the samples in ``mask`` that have truth."""
    error = np.asarray(error_rad, dtype=float)
    keep = np.isfinite(error) if mask is None else np.isfinite(error) & np.asarray(mask, dtype=bool)
    if not keep.any():
        raise ValueError("no samples with truth to score")
    e = np.degrees(error[keep])
    return {"incl_rmse_deg": float(np.sqrt(np.mean(e * e))), "incl_max_deg": float(e.max())}


def sample_periods_s(time_s) -> np.ndarray:
    """dt for each sample: the gap since the previous one; the first gets the median gap."""
    time_s = np.asarray(time_s, dtype=float)
    gaps = np.diff(time_s)
    first = np.median(gaps) if len(gaps) else 0.0
    return np.concatenate([[first], gaps])


def run_on_trial(trial, names, overrides=None) -> dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]:
    """Each named estimator (fresh, defaults + ``overrides[name]``) run over a trial: name -> (q, diag).

    The IMU axes are taken as the body axes (identity mounting): the inclination error does not
    depend on how the sensor is mounted. ValueError for an unknown name or setting.
    """
    overrides = overrides or {}
    acc_g = trial.acc_m_s2 / STANDARD_GRAVITY_M_S2
    dt_s = sample_periods_s(trial.time_s)
    return {name: create(name, overrides.get(name)).run(trial.gyr_rad_s, acc_g, dt_s) for name in dict.fromkeys(names)}


def evaluate_trial(trial, names, overrides=None) -> dict[str, dict[str, float]]:
    """Run each named estimator over a trial (``run_on_trial``) and score it against the truth."""
    if trial.true_q is None:
        raise ValueError("the file has no truth columns (true_qw ... true_qz) to evaluate against")
    mask = trial.moving if trial.moving is not None else np.ones(len(trial), dtype=bool)
    return {name: score(inclination_error_rad(q, trial.true_q), mask) for name, (q, _) in run_on_trial(trial, names, overrides).items()}

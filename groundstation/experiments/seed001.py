"""Seed 001 on the simulated car: GPS compensation of the accelerometer tilt, UKF vs SSSRUKF accuracy
and run time (the paper's figures 3 and 5 and table 1), with AHF on the same run for reference.

The car (``sim.profiles`` ``car``): up to 15 m/s, IMU 100 Hz, GPS 10 Hz with velocity and dual-antenna
heading, as in the paper's test drive. Errors are against the simulator's truth; "after convergence"
is after ``CONVERGED_S``. Run time: the whole run through each filter's ``run``, median of
``REPEATS``, both measured in this process one after the other.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from groundstation import quaternion as quat
from groundstation.estimation import create
from groundstation.estimation.tilt import acc_pitch_roll, wrap_pi
from groundstation.experiments.report import Figure, Result, Series, Table
from groundstation.sim.offline import simulate

NAME = "seed001"
TITLE = "GPS/MIMU attitude with the simple spherical simplex SRUKF (seed 001)"
CONVERGED_S = 15.0
REPEATS = 3
FILTERS = ("ukf", "sssrukf", "ahf")


def _errors_deg(pitch_roll_yaw_rad: np.ndarray, truth_q: np.ndarray) -> np.ndarray:
    """(n, 3) pitch, roll, yaw errors in degrees, wrapped; columns missing from the input stay out."""
    truth = quat.to_euler_zyx(truth_q)[:, [1, 2, 0]][:, : pitch_roll_yaw_rad.shape[1]]
    return np.degrees(wrap_pi(pitch_roll_yaw_rad - truth))


def run(quick: bool = False) -> Result:
    duration_s = 30.0 if quick else 120.0
    sim = simulate("car", duration_s, seed=1, gps_rate_hz=10.0)
    t = sim.truth.t_s
    after = t > CONVERGED_S
    raw = np.array([acc_pitch_roll(*a) for a in sim.acc_g.tolist()])
    outputs, seconds = {}, {}
    for name in FILTERS:
        times = []
        for _ in range(REPEATS if name != "ahf" else 1):
            start = time.perf_counter()
            outputs[name] = create(name).run(sim.gyr_rad_s, sim.acc_g, sim.dt_s, gps=sim.gps)
            times.append(time.perf_counter() - start)
        seconds[name] = statistics.median(times)
    diag = outputs["sssrukf"][1]
    compensated = np.column_stack([diag["acc_pitch_rad"], diag["acc_roll_rad"]])
    raw_err, comp_err = _errors_deg(raw, sim.truth.q_body_to_ned), _errors_deg(compensated, sim.truth.q_body_to_ned)

    tilt = Table(
        "Accelerometer tilt error before and after GPS compensation (after convergence)",
        ["angle", "before max (deg)", "before RMS (deg)", "after max (deg)", "after RMS (deg)", "paper"],
        [
            ["pitch", *_max_rms(raw_err[after, 0]), *_max_rms(comp_err[after, 0]), "≈7 before, < 0.5 after"],
            ["roll", *_max_rms(raw_err[after, 1]), *_max_rms(comp_err[after, 1]), "≈7 before, < 2 after"],
        ],
        notes=[
            "after: the accelerometer minus a_man = v̇_b + ω × v_b, as the sssrukf computes it on every sample",
            "our GPS velocity noise is white, 0.05 m/s per fix (the paper's receiver: < 0.02 m/s); differenced "
            "over 0.1 s it alone gives the compensated tilt ≈ 4° of noise per fix, which the filter averages",
        ],
    )
    rows = []
    for name in FILTERS:
        err = _errors_deg(quat.to_euler_zyx(outputs[name][0])[:, [1, 2, 0]], sim.truth.q_body_to_ned)[after]
        rms = np.sqrt(np.mean(err**2, axis=0))
        rows.append([name, *rms.tolist(), float(np.abs(err).max()), seconds[name], 1e6 * seconds[name] / len(t)])
    ratio = seconds["sssrukf"] / seconds["ukf"]
    accuracy = Table(
        f"Attitude error after {CONVERGED_S:.0f} s and run time on {duration_s:.0f} s of car ({len(t)} samples)",
        ["filter", "pitch RMS (deg)", "roll RMS (deg)", "yaw RMS (deg)", "max (deg)", "run time (s)", "µs/sample"],
        rows,
        notes=[
            f"run time sssrukf / ukf = {ratio:.2f} (median of {REPEATS}); paper: 0.42 (6.84 s vs 16.30 s)",
            "paper: SSSRUKF max error < 0.8° after convergence, accuracy close to the UKF's (UKF slightly better)",
            "ahf has no GPS: its yaw is gyro-only and its tilt sees the manoeuvres",
        ],
    )
    figures = [
        Figure(
            "seed001_tilt_compensation.png",
            "Accelerometer tilt error before and after GPS compensation",
            "time (s)",
            "error (deg)",
            [
                Series("pitch before", t, raw_err[:, 0]),
                Series("roll before", t, raw_err[:, 1]),
                Series("pitch after", t, comp_err[:, 0]),
                Series("roll after", t, comp_err[:, 1]),
            ],
        ),
        Figure(
            "seed001_ukf_vs_sssrukf.png",
            "Attitude error of UKF and SSSRUKF",
            "time (s)",
            "error (deg)",
            [
                Series(f"{name} {angle}", t, _errors_deg(quat.to_euler_zyx(outputs[name][0])[:, [1, 2, 0]], sim.truth.q_body_to_ned)[:, i])
                for name in ("ukf", "sssrukf")
                for i, angle in enumerate(("pitch", "roll", "yaw"))
            ],
        ),
    ]
    return Result(tables=[tilt, accuracy], figures=figures)


def _max_rms(err_deg: np.ndarray) -> list[float]:
    return [float(np.abs(err_deg).max()), float(np.sqrt(np.mean(err_deg**2)))]

"""Mounting invariance on the BROAD dev set: the same data turned through 10 random constant rotations.

    python bench/bench_mounting.py      # the first 30 s of each trial; ~10 minutes on 2 cores

For each IMU-only estimator and trial: the inclination RMSE (deg, moving samples; all samples when
the segment has none moving) of the data as recorded
and the spread (max - min) over the 10 rotations, the sensor axes ``s' = Mᵀ s`` and the truth seen from
them ``q_true ⊗ q_M``. A mounting-independent filter has a spread at rounding level.
"""

from __future__ import annotations

import sys

import numpy as np
from scipy.spatial.transform import Rotation

from groundstation import quaternion
from groundstation.datasets import read_csv
from groundstation.estimation import create
from groundstation.estimation.evaluation import inclination_error_rad, sample_periods_s, score
from groundstation.units import STANDARD_GRAVITY_M_S2

from broad import per_trial

NAMES = ["ahf", "ahf2", "hf", "ecf", "cf1", "kf", "ekf", "vqf"]
SEGMENT_S = 30.0
ROTATIONS = Rotation.random(10, random_state=13)


def trial_rows(path):
    trial = read_csv(path)
    n = int(np.searchsorted(trial.time_s, trial.time_s[0] + SEGMENT_S))
    gyr, acc = np.array(trial.gyr_rad_s[:n]), trial.acc_m_s2[:n] / STANDARD_GRAVITY_M_S2
    dt, truth, moving = sample_periods_s(trial.time_s[:n]), trial.true_q[:n], trial.moving[:n]
    if not moving.any():
        moving = None  # still all along this segment: every sample with truth
    row = {}
    for name in NAMES:
        as_recorded = score(inclination_error_rad(create(name).run(gyr, acc, dt)[0], truth), moving)["incl_rmse_deg"]
        turned = []
        for rotation in ROTATIONS:
            to_sensor = rotation.inv()
            q, _ = create(name).run(to_sensor.apply(gyr), to_sensor.apply(acc), dt)
            seen = quaternion.multiply(truth, rotation.as_quat(scalar_first=True))
            turned.append(score(inclination_error_rad(q, seen), moving)["incl_rmse_deg"])
        row[name] = (as_recorded, min(turned), max(turned))
    return path.name.split("_")[0], row


def main() -> int:
    rows = per_trial(trial_rows)
    if rows is None:
        return 1
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}; first {SEGMENT_S:.0f} s of each trial\n")
    print("RMSE as recorded / spread (max - min) over 10 random rotations, deg\n")
    print("| trial | " + " | ".join(NAMES) + " |")
    print("|---|" + "---:|" * len(NAMES))
    for trial, row in rows.items():
        print(f"| {trial} | " + " | ".join(f"{r[0]:.2f} / {r[2] - r[1]:.3f}" for r in row.values()) + " |")
    worst = {name: max(r[name][2] - r[name][1] for r in rows.values()) for name in NAMES}
    print("| **largest spread** | " + " | ".join(f"**{worst[n]:.3f}**" for n in NAMES) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

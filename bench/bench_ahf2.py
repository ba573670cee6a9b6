"""AHF2 ablation on the BROAD dev set: each part switched off in turn, one setting for every trial.

    python bench/bench_ahf2.py      # ~2 minutes on 2 idle cores (3.3 min of CPU)

Inclination RMSE (deg) over the moving samples, as in bench_estimators.py; every row is ahf2 at its
defaults with one change. The paper's ahf and vqf run in the same job for reference.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from groundstation.datasets import read_csv
from groundstation.estimation import create
from groundstation.estimation.evaluation import inclination_error_rad, sample_periods_s, score
from groundstation.units import STANDARD_GRAVITY_M_S2

from broad import per_trial

VARIANTS = {
    "ahf2 (defaults)": ("ahf2", {}),
    "λ fixed at λ_max (no adaptive step)": ("ahf2", {"adaptive": False}),
    "raw accelerometer (τ_acc = 0, no low-pass in I)": ("ahf2", {"tau_acc_s": 0.0}),
    "τ fixed at τ_acc = 5 s (no turn-rate adaptation)": ("ahf2", {"rate_ref_rad_s": math.inf}),
    "τ fixed at 3 s (VQF's)": ("ahf2", {"tau_acc_s": 3.0, "rate_ref_rad_s": math.inf}),
    "τ_acc = 3 s": ("ahf2", {"tau_acc_s": 3.0}),
    "τ_acc = 8 s": ("ahf2", {"tau_acc_s": 8.0}),
    "ω_ref = 2 rad/s": ("ahf2", {"rate_ref_rad_s": 2.0}),
    "ω_ref = 8 rad/s": ("ahf2", {"rate_ref_rad_s": 8.0}),
    "no bias at rest (no rest detection)": ("ahf2", {"rest_bias": False}),
    "no bias in motion (k_i = 0)": ("ahf2", {"motion_bias_ki": 0.0}),
    "k_i = 0.03 /s": ("ahf2", {"motion_bias_ki": 0.03}),
    "k_i = 0.3 /s": ("ahf2", {"motion_bias_ki": 0.3}),
    "no bias estimation at all": ("ahf2", {"rest_bias": False, "motion_bias_ki": 0.0}),
    "ahf (the paper's)": ("ahf", {}),
    "vqf": ("vqf", {}),
}


def trial_rows(path):
    trial = read_csv(path)
    acc_g = trial.acc_m_s2 / STANDARD_GRAVITY_M_S2
    dt = sample_periods_s(trial.time_s)
    row = {}
    for label, (name, overrides) in VARIANTS.items():
        q, _ = create(name, overrides).run(trial.gyr_rad_s, acc_g, dt)
        row[label] = score(inclination_error_rad(q, trial.true_q), trial.moving)["incl_rmse_deg"]
    return path.name.split("_")[0], row


def main() -> int:
    rows = per_trial(trial_rows)
    if rows is None:
        return 1
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}\n")
    print("| variant | " + " | ".join(rows) + " | **mean** |")
    print("|---|" + "---:|" * (len(rows) + 1))
    for label in VARIANTS:
        values = [r[label] for r in rows.values()]
        print(f"| {label} | " + " | ".join(f"{v:.2f}" for v in values) + f" | **{np.mean(values):.3f}** |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

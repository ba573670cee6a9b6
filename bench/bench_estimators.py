"""Estimator figures (printed, not asserted): per-sample cost, batch throughput, BROAD accuracy.

    python bench/bench_estimators.py            # everything (a few minutes on 2 cores)
    python bench/bench_estimators.py --no-broad # timing only

1. µs per ``step`` for each estimator, beside imufusion (the C Fusion AHRS; update + get_quaternion,
   since our step returns the quaternion) and ``ahrs.filters.Madgwick.updateIMU``, measured interleaved
   in the same run; the median of several rounds. Our inputs are tuples of Python floats (what the
   pipeline passes), imufusion's and ahrs's numpy arrays (what they need).
2. ``run`` throughput in samples/s.
3. Inclination RMSE (deg) over the moving samples of every BROAD trial in ../shared/datasets/broad (the
   dev set: the held-out trials are not on this machine, and nothing here is chosen on them) for every IMU-only estimator at its defaults (vqf is the vqf package behind our interface),
   accelerometer-only (cf1 τ = 0), gyro-only (hf β = 0), ahrs Madgwick β = 0.033 and 0.1 (fed the data
   as they are: it runs BROAD's sensor upright), and imufusion (gain 0.5, 10° acceleration rejection,
   5 s rejection timeout), all in the same run.
   All start from the first accelerometer sample (imufusion from its own start-up).
4. Heading RMSE (deg; one constant offset per trial, the mean over the moving samples, removed:
   estimation/evaluation.py, the datasets README's rule) and inclination
   of the estimators that use the magnetometer, fed it as ``evaluate`` does: hfm, ecfm, mcf, vqf (9D),
   ahf2m.
5. AHF2's settings by leave-one-trial-out: for each dev trial, the setting of ``AHF2_GRID`` (inclination)
   and of ``AHF2M_GRID`` (heading) with the lowest mean over the other dev trials, scored on that one.
   The defaults are the setting with the lowest mean over all of them at the native rate.
Sections 3-5 natively (285.7 Hz) and resampled to 100 Hz (the board's rate; ``evaluation.resampled``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import imufusion
import numpy as np
from ahrs.filters import Madgwick

from groundstation import quaternion
from groundstation.datasets import read_csv
from groundstation.estimation import ESTIMATORS, create
from groundstation.estimation.base import Estimator
from groundstation.estimation.evaluation import evaluate_trial, inclination_error_rad, resampled, sample_periods_s, score
from groundstation.units import STANDARD_GRAVITY_M_S2

from broad import per_trial

ROUNDS, CALLS = 7, 20_000


def timing_inputs(n, seed=0):
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 0.5, (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 0.1, (n, 3))
    return gyr, acc


def time_per_call_us(fn, args_list):
    start = time.perf_counter()
    for args in args_list:
        fn(*args)
    return (time.perf_counter() - start) / len(args_list) * 1e6


def bench_step():
    gyr, acc = timing_inputs(CALLS)
    ours_args = [(tuple(g), tuple(a), 0.01) for g, a in zip(gyr.tolist(), acc.tolist())]
    fusion = imufusion.Ahrs()
    fusion.set_sample_period(0.01)

    def fusion_step(g, a):
        fusion.update_no_magnetometer(g, a)
        return fusion.get_quaternion()

    fusion_args = [(g, -a) for g, a in zip(np.degrees(gyr), acc)]  # °/s and g, z up
    madgwick = Madgwick(gain=0.033)
    state = {"q": np.array([1.0, 0.0, 0.0, 0.0])}

    def ahrs_step(g, a):
        state["q"] = madgwick.updateIMU(state["q"], g, a, dt=0.01)

    ahrs_args = [(g, -a) for g, a in zip(gyr, acc)][: CALLS // 10]  # 38 µs a call: fewer calls
    rows = {name: [] for name in ["imufusion", "ahrs Madgwick", *ESTIMATORS]}
    for _ in range(ROUNDS):
        rows["imufusion"].append(time_per_call_us(fusion_step, fusion_args))
        rows["ahrs Madgwick"].append(time_per_call_us(ahrs_step, ahrs_args))
        for name in ESTIMATORS:
            est = create(name)
            calls = ours_args if name not in ("ekf", "ukf", "sssrukf") else ours_args[: CALLS // 10]
            rows[name].append(time_per_call_us(est.step, calls))
    base = statistics.median(rows["imufusion"])
    print(f"\n## step cost (median of {ROUNDS} interleaved rounds)\n")
    print("| estimator | µs/sample | × imufusion |")
    print("|---|---:|---:|")
    for name, values in rows.items():
        med = statistics.median(values)
        print(f"| {name} | {med:.2f} | {med / base:.1f} |")
    ahf32 = create("ahf").__class__(dtype=np.float32)
    f32 = statistics.median(time_per_call_us(ahf32.step, ours_args[: CALLS // 4]) for _ in range(3))
    print(f"| ahf dtype=float32 | {f32:.2f} | {f32 / base:.1f} |")


def bench_run():
    gyr, acc = timing_inputs(50_000, seed=1)
    print("\n## batch run throughput (50,000 samples)\n")
    print("| estimator | samples/s |")
    print("|---|---:|")
    for name in ESTIMATORS:
        n = len(gyr) if name not in ("ekf", "ukf", "sssrukf") else 5_000
        best = min(_run_seconds(name, gyr[:n], acc[:n]) for _ in range(3))
        print(f"| {name} | {n / best:,.0f} |")


def _run_seconds(name, gyr, acc):
    est = create(name)
    start = time.perf_counter()
    est.run(gyr, acc, 0.01)
    return time.perf_counter() - start


COLUMNS = ["ahf", "ahf2", "hf", "ecf", "cf1", "kf", "ekf", "vqf", "acc-only", "gyro-only", "ahrs β=0.033", "ahrs β=0.1", "imufusion"]
IMU_ONLY = ["ahf", "ahf2", "hf", "ecf", "cf1", "kf", "ekf", "vqf"]
OURS = {name: (name, None) for name in IMU_ONLY} | {
    "acc-only": ("cf1", {"time_constant_s": 0.0}),
    "gyro-only": ("hf", {"beta": 0.0}),
}
MAG = ["hfm", "ecfm", "mcf", "vqf", "ahf2m"]
# A few settings around the defaults (the machine is shared): the accelerometer's low-pass and the
# in-motion scale gain for the inclination, the scale gain and the magnetometer's time constant for the heading.
AHF2_GRID = {f"τ_acc {tau:g} s, k_s {ks:g}": {"tau_acc_s": tau, "motion_scale_k": ks} for tau in (5.0, 6.0, 7.0) for ks in (0.1, 0.2, 0.4)}
AHF2M_GRID = {f"k_s {ks:g}, τ_mag {tau:g} s": {"motion_scale_k": ks, "tau_mag_s": tau} for ks in (0.0, 0.01, 0.02) for tau in (9.0, 20.0, 30.0)}
UNDISTURBED = ("02", "05", "07", "09", "11", "14", "16", "21")  # 25 (tapping), 27 (vibration): disturbed in motion
MAGNET = ("31", "35")  # a magnet beside the resting sensor, one fixed to it
RATES = {"native (285.7 Hz)": None, "100 Hz (resampled)": 100.0}


def inclination_row(trial):
    acc_g = trial.acc_m_s2 / STANDARD_GRAVITY_M_S2
    dt = sample_periods_s(trial.time_s)

    def rmse(q):
        return score(inclination_error_rad(q, trial.true_q), trial.moving)["incl_rmse_deg"]

    row = {}
    for column, (name, overrides) in OURS.items():
        row[column] = rmse(create(name, overrides).run(trial.gyr_rad_s, acc_g, dt)[0])
    # ahrs Madgwick fed the data as they are (earth z up, specific force): BROAD's sensor reads +1 g on
    # z, so it runs upright; a half turn about x takes its earth frame to NED (our q0) and back.
    half_turn = np.array([0.0, 1.0, 0.0, 0.0])
    q0 = quaternion.multiply(half_turn, np.array(Estimator._attitude_from_acc(*acc_g[0], 0.0)))
    for beta in (0.033, 0.1):
        filt, q, out = Madgwick(gain=beta), q0, []
        for g, a, d in zip(trial.gyr_rad_s, acc_g, dt):
            q = filt.updateIMU(q, g, a, dt=d)
            out.append(q)
        row[f"ahrs β={beta}"] = rmse(quaternion.multiply(half_turn, np.array(out)))
    rate = 1.0 / float(np.median(dt))
    fusion = imufusion.Ahrs()
    fusion.set_settings(
        imufusion.AhrsSettings(
            sample_rate=rate,
            convention=imufusion.CONVENTION_NWU,
            gain=0.5,
            gyroscope_range=2000.0,
            acceleration_rejection=10.0,
            magnetic_rejection=0.0,
            rejection_timeout=5.0 * rate,  # in samples, as in Fusion's own examples: 5 s
        )
    )
    out = []
    for g, a, d in zip(np.degrees(trial.gyr_rad_s), acc_g, dt):
        fusion.set_sample_period(float(d))
        fusion.update_no_magnetometer(g, a)
        out.append(fusion.get_quaternion())
    # imufusion's earth z is up (NWU); a half turn about earth x makes it z-down like ours.
    row["imufusion"] = rmse(quaternion.multiply([0.0, 1.0, 0.0, 0.0], np.array(out)))
    for label, overrides in AHF2_GRID.items():
        row[label] = rmse(create("ahf2", overrides).run(trial.gyr_rad_s, acc_g, dt)[0])
    return row


def magnetometer_row(trial):
    figures = evaluate_trial(trial, MAG)
    for label, overrides in AHF2M_GRID.items():
        figures[label] = evaluate_trial(trial, ["ahf2m"], {"ahf2m": overrides})["ahf2m"]
    return figures


def broad_trial(path):
    native = read_csv(path)
    rows = {}
    for rate_label, rate_hz in RATES.items():
        trial = native if rate_hz is None else resampled(native, rate_hz)
        rows[rate_label] = {"incl": inclination_row(trial), "mag": magnetometer_row(trial)}
    return path.name.split(".")[0], rows


def trial_mean(values, trials, label):
    return np.mean([values[t][label] for t in trials])


def group_balanced_mean(values, trials, label):
    """The mean of the undisturbed trials' mean and the magnet trials' (those in ``trials``): the two
    kinds the heading is judged on count the same, however many trials each has."""
    groups = [[t for t in trials if t[:2] in prefixes] for prefixes in (UNDISTURBED, MAGNET)]
    return np.mean([trial_mean(values, members, label) for members in groups if members])


def leave_one_out(values: dict[str, dict[str, float]], grid, objective=trial_mean) -> tuple[dict[str, tuple[str, float]], str]:
    """For each trial the grid setting best on the others (lowest ``objective``) and its figure there;
    and the setting best on all."""
    trials = list(values)
    held = {}
    for trial in trials:
        others = [t for t in trials if t != trial]
        best = min(grid, key=lambda label: objective(values, others, label))
        held[trial] = (best, values[trial][best])
    return held, min(grid, key=lambda label: objective(values, trials, label))


def group_means(rows, columns):
    """Mean of each column over the dev trials of each kind (``UNDISTURBED``, ``MAGNET``)."""
    for group, prefixes in (("undisturbed", UNDISTURBED), ("magnet", MAGNET)):
        members = [r for t, r in rows.items() if t[:2] in prefixes]
        print(f"| mean, {group} ({len(members)}) | " + " | ".join(f"{np.mean([r[c] for r in members]):.3f}" for c in columns) + " |")


def table(title, rows, columns, fmt="{:.2f}"):
    print(f"\n### {title}, dev set\n")
    print("| trial | " + " | ".join(columns) + " |")
    print("|---|" + "---:|" * len(columns))
    for trial, row in rows.items():
        print(f"| {trial} | " + " | ".join(fmt.format(row[c]) for c in columns) + " |")
    print(f"| **mean (dev, {len(rows)})** | " + " | ".join(f"**{np.mean([r[c] for r in rows.values()]):.3f}**" for c in columns) + " |")
    group_means(rows, columns)
    print("| worst | " + " | ".join(f"{np.max([r[c] for r in rows.values()]):.2f}" for c in columns) + " |")


def loo_table(title, values, grid, reference, objective=trial_mean):
    """Leave-one-out over the dev trials beside the reference (VQF, same run) and the defaults' dev figures."""
    trials = list(values)
    held, chosen = leave_one_out(values, grid, objective)
    print(f"\n### {title}, dev set\n")
    print("| trial | setting chosen on the other trials | held out | VQF | held out − VQF |")
    print("|---|---|---:|---:|---:|")
    for trial, (label, figure) in held.items():
        print(f"| {trial} | {label} | {figure:.3f} | {values[trial][reference]:.3f} | {figure - values[trial][reference]:+.3f} |")
    loo = np.mean([f for _, f in held.values()])
    vqf = np.mean([values[t][reference] for t in trials])
    worst = max(f - values[t][reference] for t, (_, f) in held.items())
    print(f"| **leave-one-out mean (dev, {len(trials)})** | | **{loo:.3f}** | **{vqf:.3f}** | {loo - vqf:+.3f} ({100 * (loo / vqf - 1):+.1f} %, worst trial {worst:+.3f}) |")
    for group, prefixes in (("undisturbed", UNDISTURBED), ("magnet", MAGNET)):
        members = [t for t in trials if t[:2] in prefixes]
        print(f"| leave-one-out mean, {group} ({len(members)}) | | {np.mean([held[t][1] for t in members]):.3f} | {np.mean([values[t][reference] for t in members]):.3f} | |")
    dev = np.mean([values[t][chosen] for t in trials])
    print(f"\nChosen on all {len(trials)} dev trials (the defaults' candidate; {objective.__name__}): {chosen}, dev mean {dev:.3f} (VQF {vqf:.3f}).")


def bench_broad():
    rows = per_trial(broad_trial)
    if rows is None:
        return
    for rate_label in RATES:
        print(f"\n## BROAD, {rate_label}")
        incl = {t: r[rate_label]["incl"] for t, r in rows.items()}
        mag = {t: r[rate_label]["mag"] for t, r in rows.items()}
        table("Inclination RMSE (deg), moving samples, every IMU-only estimator at its defaults", incl, COLUMNS)
        table("With the magnetometer: heading RMSE (deg), one offset per trial removed", mag_rows(mag, "heading_rmse_deg"), MAG)
        table("With the magnetometer: inclination RMSE (deg)", mag_rows(mag, "incl_rmse_deg"), MAG)
        loo_table("AHF2 inclination, leave-one-trial-out over AHF2_GRID", incl, AHF2_GRID, "vqf")
        heading = {t: {label: m[label]["heading_rmse_deg"] for label in [*AHF2M_GRID, "vqf"]} for t, m in mag.items() if t[:2] in UNDISTURBED + MAGNET}
        loo_table("AHF2M heading, leave-one-trial-out over AHF2M_GRID, undisturbed and magnet trials", heading, AHF2M_GRID, "vqf", group_balanced_mean)


def mag_rows(mag, key):
    return {t: {name: m[name][key] for name in MAG} for t, m in mag.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-broad", action="store_true", help="timing only")
    args = parser.parse_args()
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}")
    bench_step()
    bench_run()
    if not args.no_broad:
        bench_broad()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The compiled estimator kernels (estimation/base.py) against the code before them, vqf and imufusion.

    PYTHONPATH=. python bench/bench_kernels.py [--rounds R] [--calls N] [--samples N] [--no-broad]

All in one run, on the same flight-like samples (100 Hz):

1. µs per ``step`` of each compiled estimator, now and before (the tree at ``BEFORE``, the last commit
   with the per-sample Python estimators, extracted with ``git archive``), beside imufusion's C
   ``update_no_magnetometer`` + ``get_quaternion`` (tuples of Python floats in for ours, numpy arrays
   for imufusion, what each takes). Medians of R rounds, the trees alternating round by round so that
   the machine's load falls on both alike.
2. ``run`` in samples/s, now and before, beside ``vqf.VQF.updateBatch`` (C++); and the estimators part of
   issue 15's budget: ahf, hf and ecf over one hour at 100 Hz (360,000 samples).
3. numba's compile time: a fresh process creates every compiled estimator and runs one batch, with an
   empty cache directory (the first use on a machine: compiles, writes the cache) and again with the
   same directory (every later start: loads it); the imports apart.
4. Accuracy unchanged: the BROAD dev set's mean inclination RMSE (moving samples) of each compiled
   estimator at its defaults, now and before (skipped without ../shared/datasets/broad).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BEFORE = "d9ec648"  # the last commit before the compiled kernels
NAMES = ["ahf", "hf", "ecf", "cf1", "kf", "ekf", "hfm", "ecfm"]
SLOW_BEFORE = {"ekf": 10}  # fewer calls where the old step took ~70 µs
HOUR = 360_000


def flight_like(n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 0.3, (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 0.1, (n, 3))
    mag = np.array([20.0, 0.0, 40.0]) + rng.normal(0.0, 1.0, (n, 3))
    return gyr, acc, mag


# -- measured inside a process whose PYTHONPATH is one tree --------------------------------------


def worker_round(calls: int, samples: int) -> dict:
    """One round of step µs and run samples/s for every estimator of this tree."""
    from groundstation.estimation import create

    gyr, acc, mag = flight_like(max(calls, samples))
    args = [(tuple(g), tuple(a), 0.01, tuple(m)) for g, a, m in zip(gyr.tolist(), acc.tolist(), mag.tolist())]
    out = {"step_us": {}, "run_per_s": {}}
    for name in NAMES:
        est = create(name)
        est.run(gyr[:10], acc[:10], 0.01, mag=mag[:10])  # compiled (or loaded) before timing
        n = calls // SLOW_BEFORE.get(name, 1)
        step = est.step
        t0 = time.perf_counter()
        for g, a, d, m in args[:n]:
            step(g, a, d, m)
        out["step_us"][name] = (time.perf_counter() - t0) / n * 1e6
        m = samples // SLOW_BEFORE.get(name, 1)
        t0 = time.perf_counter()
        est.run(gyr[:m], acc[:m], 0.01, mag=mag[:m])
        out["run_per_s"][name] = m / (time.perf_counter() - t0)
    return out


def worker_broad() -> dict:
    from groundstation.datasets import read_csv
    from groundstation.estimation import create
    from groundstation.estimation.evaluation import inclination_error_rad, sample_periods_s, score
    from groundstation.units import STANDARD_GRAVITY_M_S2

    rmse = {name: [] for name in NAMES[:6]}
    for path in sorted((ROOT / ".." / "shared" / "datasets" / "broad").glob("*.csv*")):
        trial = read_csv(path)
        for name in rmse:
            q, _ = create(name).run(trial.gyr_rad_s, trial.acc_m_s2 / STANDARD_GRAVITY_M_S2, sample_periods_s(trial.time_s))
            rmse[name].append(score(inclination_error_rad(q, trial.true_q), trial.moving)["incl_rmse_deg"])
    return {name: float(np.mean(v)) for name, v in rmse.items() if v}


def worker_compile() -> dict:
    t0 = time.perf_counter()
    from groundstation.estimation import create

    imports = time.perf_counter() - t0
    gyr, acc, mag = flight_like(10)
    t0 = time.perf_counter()
    for name in NAMES:
        create(name).run(gyr, acc, 0.01, mag=mag)
    return {"imports_s": imports, "first_use_s": time.perf_counter() - t0}


def in_tree(tree: Path, task: str, *args, cache_dir: str | None = None) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree))
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    cmd = [sys.executable, __file__, "--worker", task, *map(str, args)]
    return json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout)


# -- baselines and the report -------------------------------------------------------------------


def baselines(calls: int, samples: int, rounds: int) -> tuple[float, float]:
    """imufusion µs per step and vqf updateBatch samples/s, medians of ``rounds``."""
    import imufusion
    from vqf import VQF

    from groundstation.units import STANDARD_GRAVITY_M_S2

    gyr, acc, _ = flight_like(max(calls, samples))
    fusion = imufusion.Ahrs()
    fusion.set_sample_period(0.01)
    fusion_args = [(g, -a) for g, a in zip(np.degrees(gyr[:calls]), acc[:calls])]  # °/s, g, z up

    def fusion_us():
        t0 = time.perf_counter()
        for g, a in fusion_args:
            fusion.update_no_magnetometer(g, a)
            fusion.get_quaternion()
        return (time.perf_counter() - t0) / calls * 1e6

    g, a = np.ascontiguousarray(gyr[:samples]), np.ascontiguousarray(-acc[:samples] * STANDARD_GRAVITY_M_S2)

    def vqf_per_s():
        t0 = time.perf_counter()
        VQF(0.01).updateBatch(g, a)
        return samples / (time.perf_counter() - t0)

    return statistics.median(fusion_us() for _ in range(rounds)), statistics.median(vqf_per_s() for _ in range(rounds))


def hour_seconds(rounds: int) -> float:
    """ahf + hf + ecf ``run`` over one hour at 100 Hz, median of ``rounds``."""
    from groundstation.estimation import create

    gyr, acc, _ = flight_like(HOUR)
    for name in ("ahf", "hf", "ecf"):
        create(name).run(gyr[:10], acc[:10], 0.01)
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for name in ("ahf", "hf", "ecf"):
            create(name).run(gyr, acc, 0.01)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def extract_before(folder: str) -> Path:
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", BEFORE, "groundstation"], capture_output=True, check=True).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    return Path(folder)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=20_000, help="step calls per round (ekf before: a tenth)")
    parser.add_argument("--samples", type=int, default=100_000, help="run samples per round (ekf before: a tenth)")
    parser.add_argument("--no-broad", action="store_true")
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        task, *rest = args.worker
        work = {"round": lambda: worker_round(*map(int, rest)), "broad": worker_broad, "compile": worker_compile}[task]
        print(json.dumps(work()))
        return
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, load average {os.getloadavg()[0]:.1f} at the start\n")
    with tempfile.TemporaryDirectory() as old_dir, tempfile.TemporaryDirectory() as cache:
        old = extract_before(old_dir)
        first = in_tree(ROOT, "compile", cache_dir=cache)
        cached = in_tree(ROOT, "compile", cache_dir=cache)
        rounds = {"now": [], "before": []}
        for _ in range(args.rounds):
            for tree, key in ((ROOT, "now"), (old, "before")):
                rounds[key].append(in_tree(tree, "round", args.calls, args.samples))
        fusion_us, vqf_per_s = baselines(args.calls, args.samples, args.rounds)
        hour = hour_seconds(args.rounds)
        broad = None if args.no_broad else {key: in_tree(tree, "broad") for tree, key in ((ROOT, "now"), (old, "before"))}

    def med(key, kind, name):
        return statistics.median(r[kind][name] for r in rounds[key])

    print(f"## step and run (medians of {args.rounds} rounds; before = {BEFORE}, per-sample Python)\n")
    print(f"imufusion step (C): {fusion_us:.2f} µs; vqf updateBatch (C++): {vqf_per_s / 1e6:.2f} M samples/s\n")
    print("| estimator | step µs before | step µs now | × faster | now / imufusion | run before (samples/s) | run now (samples/s) | × faster | now / vqf |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in NAMES:
        sb, sn = med("before", "step_us", name), med("now", "step_us", name)
        rb, rn = med("before", "run_per_s", name), med("now", "run_per_s", name)
        print(f"| {name} | {sb:.2f} | {sn:.2f} | {sb / sn:.1f} | {sn / fusion_us:.1f} | {rb:,.0f} | {rn:,.0f} | {rn / rb:.0f} | {rn / vqf_per_s:.2f} |")
    print(f"\nahf + hf + ecf run over one hour at 100 Hz ({HOUR:,} samples): {hour:.2f} s (issue 15's budget for replay + the three: 7.2 s)")
    print("\n## numba compile time (a fresh process: every compiled estimator created and run once)\n")
    print("| | imports (numpy, numba, estimators) | first use of the kernels |")
    print("|---|---:|---:|")
    print(f"| first run on a machine (empty cache: compile, write) | {first['imports_s']:.2f} s | {first['first_use_s']:.2f} s |")
    print(f"| every later run (cache loaded) | {cached['imports_s']:.2f} s | {cached['first_use_s']:.2f} s |")
    if broad and broad["now"]:
        print("\n## BROAD dev set, mean inclination RMSE (deg), moving samples, defaults\n")
        print("| | " + " | ".join(broad["now"]) + " |")
        print("|---|" + "---:|" * len(broad["now"]))
        for key in ("before", "now"):
            print(f"| {key} | " + " | ".join(f"{broad[key][n]:.4f}" for n in broad["now"]) + " |")


if __name__ == "__main__":
    main()

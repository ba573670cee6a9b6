"""Every estimator's cost per sample in ``run``, beside imufusion and VQF's C++ batch, in one run.

    PYTHONPATH=. python bench/bench_estimator_costs.py [--rounds R] [--samples N] [--no-broad]
    PYTHONPATH=. python bench/bench_estimator_costs.py --recording REC [--baseline TREE] [--rounds R]

``--recording``: section 1 only, on a recording's own samples: each live estimator's ``run`` as an export
calls it (``EstimateRun.stretches``: every stretch of the session, the readings its samples were handed),
CPU µs per sample, in a fresh process per round; ``--baseline``: the same in another checkout of the project
(its own numba cache), the two trees' processes interleaved round by round, medians of R.

1. CPU µs per sample of each estimator's ``run`` (the batch path: opening a recording) on flight-like
   samples at 100 Hz whose times jitter by 0.2 % (as the recordings'), a magnetometer reading on every
   fourth sample and a GPS fix (NED velocity, heading) on every tenth, so every estimator gets the
   aiding it uses; beside imufusion's C ``update_no_magnetometer`` + ``get_quaternion`` called from
   Python per sample (it has no batch call) and ``vqf.VQF.updateBatch`` with the period fixed (C++).
   Medians of R rounds, the estimators and baselines interleaved round by round so that the machine's
   load falls on all alike; process time, not wall time (the machine is shared). The SSSRUKF/UKF ratio
   of the same medians, against seed 001's 42 % (6.84 s vs 16.30 s), and why: the operations of each
   step of the two filters at n = 4 (``ukf_step_costs``: flops, divisions and square roots, libm calls),
   counted from the loops of estimation/sigma_points.py and small_linalg.py.
2. numba's compile time: a fresh process creates every estimator and runs one batch, with an empty
   cache directory (the first start on a machine: compile, write) and again with that directory (every
   later start: load); imports apart.
3. The sample-time jitter VQF does not integrate (vqf.py: its coefficients are for one period): on the
   BROAD trials (../shared/datasets/broad), VQF's inclination and heading RMSE (moving samples,
   estimation/evaluation.py; heading with one offset per trial removed) with the gyro as recorded, and
   with each sample's rate scaled by 1 + ε, ε ~ N(0, σ): exactly the angle a filter integrating the
   fixed period instead of a sample interval jittering by σ gets wrong.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
JITTER = 0.002  # relative sample-interval jitter of the recordings


def inputs(n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 0.3, (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 0.1, (n, 3))
    dt = 0.01 * (1.0 + rng.normal(0.0, JITTER, n))
    mag = np.full((n, 3), np.nan)
    mag[::4] = np.array([20.0, 0.0, 40.0]) + rng.normal(0.0, 1.0, (len(mag[::4]), 3))
    gps = np.full((n, 4), np.nan)
    gps[::10] = np.column_stack([np.cumsum(rng.normal(0.0, 0.1, (len(gps[::10]), 3)), axis=0), rng.uniform(-np.pi, np.pi, len(gps[::10]))])
    return gyr, acc, dt, mag, gps


def _cholesky(n):
    """(flops, div, sqrt) of small_linalg.cholesky on n x n."""
    return sum(2 * j + (n - 1 - j) * 2 * j for j in range(n)), n * (n - 1) // 2, n


def _tria(rows, cols):
    """(flops, div, sqrt) of small_linalg.tria on rows x cols (Householder, one vector per row)."""
    flops = sum(2 * (cols - k) + 4 + (rows - 1 - k) * (4 * (cols - k) + 2) for k in range(rows))
    return flops, rows, rows


def _cholupdate(n):
    """(flops, div, sqrt) of small_linalg.cholupdate of an n x n factor."""
    return n + sum(5 + 5 * (n - 1 - k) for k in range(n)), sum(2 + (n - 1 - k) for k in range(n)), n + 1


def _solve_right(m, rows):
    return 2 * rows * m * (m - 1), 2 * rows * m, 0


def _add(*costs):
    return tuple(sum(c[i] for c in costs) for i in range(3))


def ukf_step_costs(square_root: bool, n: int = 4, m: int = 3) -> dict[str, tuple]:
    """Per step of one sample of ukf (dense, symmetric set, 2n + 1 points) or sssrukf (square root,
    spherical simplex, n + 2 points) with m linear measurements (gravity's direction, ukf.py): (flops, divisions, square roots, libm
    calls), counted from the loops of sigma_points.py and small_linalg.py (adds and multiplies; a
    compare is not counted)."""
    count = n + 2 if square_root else 2 * n + 1
    nnz = n * (n + 3) // 2 if square_root else 2 * n  # nonzero unit-set entries: χ = x + S z skips the zeros
    points = (2 * n * nnz, 0, 0)
    no_libm = 0
    steps = {}
    steps["factor P (ukf: Cholesky; sssrukf: carried)"] = (*(0, 0, 0), no_libm) if square_root else (*_cholesky(n), no_libm)
    steps["sigma points x + S z"] = (*points, no_libm)
    steps["propagate the points (integrate_rate: pow)"] = (40 * count, 0, 0, count)
    spread = (3 * n * count, 0, 0)
    if square_root:  # QR of [√wc (χ - x), √Q], one cholupdate with the centre point
        time = _add(spread, (n * (count - 1), 0, 0), _tria(n, count - 1 + n), _cholupdate(n))
    else:  # Σ wc (χ - x)(χ - x)ᵀ + Q, its upper triangle
        time = _add(spread, (3 * count * n * (n + 1) // 2 + n, 0, 0))
    steps["time update"] = (*time, no_libm)
    steps["factor P⁻ (ukf: Cholesky; sssrukf: carried)"] = (*(0, 0, 0), no_libm) if square_root else (*_cholesky(n), no_libm)
    steps["sigma points again"] = (*points, no_libm)
    steps["gravity's direction of the points (down_in_body)"] = (count * (7 + 4 + 4 + 7), 3 * count, 0, 0)
    outputs = (3 * m * count + n * count + m, 0, 0)
    p_xy = (3 * count * n * m, 0, 0)
    corrected = (2 * n * m + n, 0, 0)
    if square_root:  # Sy by QR and cholupdate, K = Pxy / Syᵀ / Sy, S downdated by the m columns of K Sy
        update = _add(outputs, (m * (count - 1), 0, 0), _tria(m, count - 1 + m), _cholupdate(m), p_xy, _solve_right(m, n),
                      (2 * n * m * m, 0, 0), *[_cholupdate(n)] * m, corrected)
    else:  # Pyy, Pxy, K = Pxy Pyy⁻¹ by Cholesky, P - K Pxyᵀ
        update = _add(outputs, (3 * count * m * (m + 1) // 2 + m, 0, 0), p_xy, _cholesky(m), _solve_right(m, n), corrected,
                      ((2 * m + 2) * n * (n + 1) // 2, 0, 0))
    steps["measurement update"] = (*update, 0)  # linear rows: no innovation wrapped
    return steps


def print_step_costs() -> None:
    print("\n## ukf and sssrukf: operations per sample by step (n = 4, a gravity update: m = 3; a fix with heading adds a fourth row)\n")
    print("| step | ukf flops / div / sqrt / libm | sssrukf flops / div / sqrt / libm |")
    print("|---|---:|---:|")
    dense, root = ukf_step_costs(False), ukf_step_costs(True)
    for step in dense:
        print(f"| {step} | " + " | ".join(" / ".join(str(v) for v in c[step]) for c in (dense, root)) + " |")
    total = [tuple(sum(c[i] for c in costs.values()) for i in range(4)) for costs in (dense, root)]
    print("| **total** | " + " | ".join(" / ".join(str(v) for v in t) for t in total) + " |")
    print(f"\nsssrukf / ukf: flops {total[1][0] / total[0][0]:.0%}, divisions + square roots "
          f"{(total[1][1] + total[1][2]) / (total[0][1] + total[0][2]):.0%}, libm calls {total[1][3] / total[0][3]:.0%}")


def cpu_us_per_sample(function, n: int) -> float:
    t0 = time.process_time()
    function()
    return (time.process_time() - t0) / n * 1e6


def costs(samples: int, rounds: int) -> dict[str, float]:
    import imufusion
    from vqf import VQF

    from groundstation.estimation import ESTIMATORS, create
    from groundstation.units import STANDARD_GRAVITY_M_S2

    gyr, acc, dt, mag, gps = inputs(samples)
    for name in ESTIMATORS:  # compiled (or loaded) before timing
        create(name).run(gyr[:20], acc[:20], dt[:20], mag=mag[:20], gps=gps[:20])
    fusion_args = [(g, -a) for g, a in zip(np.degrees(gyr), acc)]  # °/s, g, z up
    g_c, a_c = np.ascontiguousarray(gyr), np.ascontiguousarray(-acc * STANDARD_GRAVITY_M_S2)

    def fusion():
        ahrs = imufusion.Ahrs()
        ahrs.set_sample_period(0.01)
        for g, a in fusion_args:
            ahrs.update_no_magnetometer(g, a)
            ahrs.get_quaternion()

    times = {name: [] for name in ["imufusion (C, per sample)", "vqf updateBatch (C++)", *ESTIMATORS]}
    for _ in range(rounds):
        times["imufusion (C, per sample)"].append(cpu_us_per_sample(fusion, samples))
        times["vqf updateBatch (C++)"].append(cpu_us_per_sample(lambda: VQF(0.01).updateBatch(g_c, a_c), samples))
        for name in ESTIMATORS:
            est = create(name)
            times[name].append(cpu_us_per_sample(lambda: est.run(gyr, acc, dt, mag=mag, gps=gps), samples))
    return {name: statistics.median(v) for name, v in times.items()}


def worker_recording(path: str) -> dict:
    """CPU s of each live estimator's ``run`` over a recording, called as an export calls it: the session's
    estimates streamed (``load_session(stream_estimates=True)``) and read forward, every row."""
    from groundstation.estimation import ESTIMATORS, live_estimators
    from groundstation.session_makers.load import load_session

    names = live_estimators()
    spent = dict.fromkeys(names, 0.0)
    samples = dict.fromkeys(names, 0)

    def timed(run):
        def run_timed(self, gyr, *args):
            t0 = time.process_time()
            out = run(self, gyr, *args)
            spent[self.name] += time.process_time() - t0
            samples[self.name] += len(gyr)
            return out

        return run_timed

    # each class that defines the run the estimators use, once (a subclass's inherited run is its base's)
    owners = {next(c for c in ESTIMATORS[name].__mro__ if "run" in vars(c)) for name in names}
    for owner in owners:
        owner.run = timed(vars(owner)["run"])
    data = load_session(path, names, stream_estimates=True)
    for name in names:  # the compiled ones were loaded from the cache with the session; vqf's screen too
        ESTIMATORS[name].runs_compiled()
    rows = len(data.tables["imu"]["time_s"])
    for start in range(0, rows, 65_536):
        data.estimates.at(np.arange(start, min(start + 65_536, rows)))
    return {name: spent[name] / samples[name] * 1e6 for name in names}


def recording_costs(path: str, trees: list[Path], rounds: int) -> dict[Path, dict[str, float]]:
    """``worker_recording`` in a fresh process per tree and round, the trees interleaved; medians."""
    runs = {tree: [] for tree in trees}
    for _ in range(rounds):
        for tree in trees:
            env = dict(os.environ, PYTHONPATH=str(tree))
            cmd = [sys.executable, __file__, "--worker-recording", path]
            runs[tree].append(json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=tree).stdout))
    return {tree: {name: statistics.median(r[name] for r in rs) for name in rs[0]} for tree, rs in runs.items()}


def print_recording_costs(path: str, trees: list[Path], rounds: int) -> None:
    med = recording_costs(path, trees, rounds)
    print(f"## run on {path}: CPU µs per sample as an export calls it (medians of {rounds} interleaved rounds)\n")
    print("| estimator | " + " | ".join(str(t) for t in trees) + (" | ratio |" if len(trees) > 1 else ""))
    print("|---|" + "---:|" * (len(trees) + (len(trees) > 1)))
    names = list(med[trees[0]])
    for name in [*names, "all"]:
        values = [sum(m.values()) if name == "all" else m[name] for m in (med[t] for t in trees)]
        ratio = f" | {values[0] / values[1]:.2f}" if len(trees) > 1 else ""
        print(f"| {name} | " + " | ".join(f"{v:.3f}" for v in values) + ratio + " |")
    this = med[trees[0]]
    print(f"\nSSSRUKF / UKF run time ({trees[0]}): {this['sssrukf'] / this['ukf']:.0%} (seed 001: 42 %)")


def worker_compile() -> dict:
    """Process time (CPU s) of the imports and of each estimator's first creation and run."""
    t0 = time.process_time()
    from groundstation.estimation import ESTIMATORS, create

    imports = time.process_time() - t0
    gyr, acc, dt, mag, gps = inputs(20)
    first = {}
    for name in ESTIMATORS:
        t0 = time.process_time()
        create(name).run(gyr, acc, dt, mag=mag, gps=gps)
        first[name] = time.process_time() - t0
    return {"imports_s": imports, "first_use_s": first}


def compile_times() -> tuple[dict, dict]:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=cache)
        cmd = [sys.executable, __file__, "--worker-compile"]
        fresh, cached = (json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout) for _ in range(2))
    return fresh, cached


def jitter_trial(path) -> tuple[str, dict]:
    from groundstation.datasets import read_csv
    from groundstation.estimation.evaluation import evaluate_trial, resampled

    trial = read_csv(path)
    row = {}
    for rate, t in (("native", trial), ("100 Hz", resampled(trial, 100.0))):
        for sigma in (0.0, JITTER, 10 * JITTER):
            scale = 1.0 + np.random.default_rng(0).normal(0.0, sigma, (len(t.time_s), 1))
            jittered = dataclasses.replace(t, gyr_rad_s=t.gyr_rad_s * scale)
            row[f"{rate} σ={sigma:g}"] = evaluate_trial(jittered, ["vqf"])["vqf"]
    return path.name.split("_")[0], row


def print_compile_times(fresh, cached) -> None:
    print("\n## numba compile time, CPU s (a fresh process: every estimator created and run once, in this order)\n")
    print("| | imports | " + " | ".join(fresh["first_use_s"]) + " | all |")
    print("|---|---:|" + "---:|" * (len(fresh["first_use_s"]) + 1))
    for label, r in (("first start on a machine (empty cache)", fresh), ("every later start (cache loaded)", cached)):
        first = r["first_use_s"]
        print(f"| {label} | {r['imports_s']:.2f} | " + " | ".join(f"{v:.2f}" for v in first.values()) + f" | {sum(first.values()):.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--samples", type=int, default=30_000)
    parser.add_argument("--no-broad", action="store_true")
    parser.add_argument("--compile-only", action="store_true", help="section 2 alone")
    parser.add_argument("--recording", help="section 1 only, on this recording's samples as an export runs them")
    parser.add_argument("--baseline", type=Path, help="with --recording: another checkout measured alongside")
    parser.add_argument("--worker-compile", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--worker-recording", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker_compile:
        print(json.dumps(worker_compile()))
        return
    if args.worker_recording:
        print(json.dumps(worker_recording(args.worker_recording)))
        return
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, load average {os.getloadavg()[0]:.1f} at the start\n")
    if args.recording:
        trees = [ROOT] + ([args.baseline.resolve()] if args.baseline else [])
        print_recording_costs(args.recording, trees, args.rounds)
        print(f"\nload average {os.getloadavg()[0]:.1f} at the end")
        return
    fresh, cached = compile_times()
    if args.compile_only:
        print_compile_times(fresh, cached)
        return
    med = costs(args.samples, args.rounds)
    fusion = med["imufusion (C, per sample)"]
    print(f"## run: CPU µs per sample (medians of {args.rounds} interleaved rounds, {args.samples:,} samples, 100 Hz ± {JITTER:.1%})\n")
    print("| estimator | µs/sample | × imufusion |")
    print("|---|---:|---:|")
    for name, us in med.items():
        print(f"| {name} | {us:.2f} | {us / fusion:.1f} |")
    print(f"\nSSSRUKF / UKF run time: {med['sssrukf'] / med['ukf']:.0%} (seed 001: 42 %, 6.84 s vs 16.30 s)")
    print_step_costs()
    print_compile_times(fresh, cached)
    if args.no_broad:
        return
    sys.path.insert(0, str(Path(__file__).parent))
    from broad import per_trial

    rows = per_trial(jitter_trial)
    if not rows:
        return
    columns = list(next(iter(rows.values())))
    print("\n## VQF on BROAD with the gyro scaled by 1 + ε, ε ~ N(0, σ) (the sample-interval jitter a fixed period does not integrate)\n")
    print("| trial | " + " | ".join(f"{c} incl / heading RMSE °" for c in columns) + " |")
    print("|---|" + "---:|" * len(columns))
    for trial, row in rows.items():
        print(f"| {trial} | " + " | ".join(f"{row[c]['incl_rmse_deg']:.3f} / {row[c]['heading_rmse_deg']:.3f}" for c in columns) + " |")
    mean = {c: (np.mean([r[c]["incl_rmse_deg"] for r in rows.values()]), np.mean([r[c]["heading_rmse_deg"] for r in rows.values()])) for c in columns}
    print("| mean | " + " | ".join(f"{m[0]:.4f} / {m[1]:.4f}" for m in mean.values()) + " |")


if __name__ == "__main__":
    main()

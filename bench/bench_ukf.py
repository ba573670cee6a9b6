"""Per-sample cost of seed 001's ukf and sssrukf (printed, not asserted), ahf as the baseline.

    python bench/bench_ukf.py

``step`` on a simulated car run with GPS at 10 Hz (so the heading and compensation paths run), the
filters interleaved in each round, the median of ``ROUNDS`` rounds; the ratio sssrukf / ukf is the
paper's run-time comparison (seed 001 table 1: 0.42).
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from groundstation.estimation import create
from groundstation.estimation.base import GpsFix
from groundstation.sim.offline import simulate

ROUNDS, SECONDS = 5, 20.0
NAMES = ("ahf", "ukf", "sssrukf")


def main() -> int:
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}")
    sim = simulate("car", SECONDS, seed=2, gps_rate_hz=10.0)
    fixes = [None if np.isnan(r).all() else GpsFix(*r) for r in sim.gps.tolist()]
    samples = list(zip(sim.gyr_rad_s.tolist(), sim.acc_g.tolist(), fixes))
    rows = {name: [] for name in NAMES}
    for _ in range(ROUNDS):
        for name in NAMES:
            est = create(name)
            start = time.perf_counter()
            for g, a, f in samples:
                est.step(g, a, sim.dt_s, gps=f)
            rows[name].append((time.perf_counter() - start) / len(samples) * 1e6)
    base = statistics.median(rows["ahf"])
    print(f"\n## step cost on {SECONDS:.0f} s of car, GPS 10 Hz (median of {ROUNDS} interleaved rounds)\n")
    print("| estimator | µs/sample | × ahf |")
    print("|---|---:|---:|")
    for name, values in rows.items():
        med = statistics.median(values)
        print(f"| {name} | {med:.1f} | {med / base:.0f} |")
    ratio = statistics.median(s / u for s, u in zip(rows["sssrukf"], rows["ukf"]))
    print(f"\nsssrukf / ukf = {ratio:.2f} (median of the per-round ratios; paper: 0.42)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Compiled batch estimator kernels: throughput against the current ``run`` and vqf's C++ ``updateBatch``,
and numba's compile time on the first call on a machine and from its cache.

    PYTHONPATH=. python bench/bench_kernels.py [--samples N] [--repeats R]

1. samples/s of ``ahf``, ``hf``, ``ecf``: ``create(name).run`` (per-sample ``step``, today's path),
   the kernel (``groundstation.estimation.kernels``), and ``vqf.VQF.updateBatch`` (a C++ 6D filter
   with bias estimation and rest detection: the compiled baseline), on the same flight-like samples
   in the same run; medians of R repeats. The kernels are checked equal to ``run`` before timing.
2. Compile time: a fresh Python process calls the three kernels once on 10 samples, with an empty
   numba cache directory (first run on a machine: compiles and writes the cache), then again with the
   same directory (every later run: loads the cache). The imports are timed apart.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import median_seconds
from vqf import VQF

from groundstation.estimation import create
from groundstation.estimation.kernels import run_ahf, run_ecf
from groundstation.units import STANDARD_GRAVITY_M_S2

ROOT = Path(__file__).resolve().parents[1]
KERNELS = {"ahf": run_ahf, "hf": run_ahf, "ecf": run_ecf}
FIRST_CALL = """
import time, numpy as np
t0 = time.perf_counter()
from groundstation.estimation import create
from groundstation.estimation.kernels import run_ahf, run_ecf
t1 = time.perf_counter()
g, a, d = np.zeros((10, 3)), np.tile([0.0, 0.0, -1.0], (10, 1)), np.full(10, 0.01)
for name, run in (("ahf", run_ahf), ("hf", run_ahf), ("ecf", run_ecf)):
    run(create(name).settings, g, a, d)
print(t1 - t0, time.perf_counter() - t1)
"""


def flight_like(n: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 0.3, (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 0.1, (n, 3))
    return gyr, acc, np.full(n, 0.01)


def median_rate(function, n: int, repeats: int) -> float:
    return n / median_seconds(function, repeats)


def import_and_first_call_seconds(cache_dir: str) -> tuple[float, float]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, capture_output=True, text=True, check=True)
    imports, first_call = map(float, out.stdout.split())
    return imports, first_call


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    n = args.samples
    gyr, acc, dt = flight_like(n)
    print(f"{n} flight-like samples at 100 Hz; medians of {args.repeats} repeats")
    vqf_acc = -acc * STANDARD_GRAVITY_M_S2  # vqf: m/s², z up at rest in its frame; only the cost matters
    vqf_rate = median_rate(lambda: VQF(0.01).updateBatch(np.ascontiguousarray(gyr), np.ascontiguousarray(vqf_acc)), n, args.repeats)
    print(f"vqf updateBatch (C++):        {vqf_rate / 1e6:6.2f} M samples/s")
    for name, kernel in KERNELS.items():
        settings = create(name).settings
        q_run, _ = create(name).run(gyr, acc, dt)
        q_kernel, _ = kernel(settings, gyr, acc, dt)  # also compiles (or loads) before timing
        assert np.array_equal(q_run, q_kernel), name
        run_rate = median_rate(lambda: create(name).run(gyr, acc, dt), n, args.repeats)
        kernel_rate = median_rate(lambda: kernel(settings, gyr, acc, dt), n, args.repeats)
        print(
            f"{name:4s} run (step loop) {run_rate / 1e6:6.3f} M/s   kernel {kernel_rate / 1e6:6.2f} M/s   "
            f"= {kernel_rate / run_rate:5.0f} x run, {kernel_rate / vqf_rate:5.2f} x vqf"
        )
    with tempfile.TemporaryDirectory() as cache:
        imports, first = import_and_first_call_seconds(cache)
        imports_cached, cached = import_and_first_call_seconds(cache)
    print(
        f"numba, first call of the 3 kernels: first run on a machine {first:.2f} s (compile + write cache), "
        f"later runs {cached:.2f} s (cache load); imports (numpy, numba, estimators) {imports:.2f} s / {imports_cached:.2f} s beside"
    )


if __name__ == "__main__":
    main()

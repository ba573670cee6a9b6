"""Position filter figures (printed, not asserted): µs per sample of each seed 004 filter.

    python bench/bench_position.py > bench/bench_position.out.md

Inputs are a simulated flight (100 Hz IMU, barometer 25 Hz, GPS 10 Hz) as the live pipeline passes
them: tuples of Python floats, a reading only on its sample. Baseline measured interleaved in the same
rounds: ``ahf``'s ``step`` (the attitude filter the pipeline runs on every sample anyway). Each figure is
the median of ROUNDS rounds; the ratio is to the baseline's median.
"""

from __future__ import annotations

import platform
import statistics
import time

import numpy as np

from groundstation.estimation import create
from groundstation.position import DualChannel, SingleChannel, linear_acc_ned_m_s2
from groundstation.sim.offline import simulate

ROUNDS, SECONDS = 7, 100.0


def _maybe(row):
    return None if np.isnan(row).all() else tuple(row)


def main() -> None:
    sim = simulate("flight", SECONDS, seed=7, baro_rate_hz=25, gps_rate_hz=10)
    dt = sim.dt_s
    q = create("ahf").run(sim.gyr_rad_s, sim.acc_g, dt)[0]
    acc = linear_acc_ned_m_s2(sim.acc_g, q)
    baro = [None if np.isnan(h) else h for h in sim.baro_alt_m.tolist()]
    gps_pos = [_maybe(r) for r in sim.gps_pos_ned_m.tolist()]
    gps_vel = [_maybe(r) for r in sim.gps[:, :3].tolist()]
    acc_t, acc_g_t, q_t = [tuple(r) for r in acc.tolist()], [tuple(r) for r in sim.acc_g.tolist()], [tuple(r) for r in q.tolist()]
    gyr_t = [tuple(r) for r in sim.gyr_rad_s.tolist()]
    n = len(sim)

    def ahf_step():
        step = create("ahf").step
        for g, a in zip(gyr_t, acc_g_t):
            step(g, a, dt)

    def rotate():
        for a, qq in zip(acc_g_t, q_t):
            linear_acc_ned_m_s2(a, qq)

    def filter_step(cls, with_vel):
        def go():
            step = cls().step
            for a, h, z, u in zip(acc_t, baro, gps_pos, gps_vel if with_vel else [None] * n):
                step(a, dt, h, z, u)
        return go

    def filter_run():
        DualChannel().run(acc, dt, sim.baro_alt_m, sim.gps_pos_ned_m, sim.gps[:, :3])

    cases = {
        "ahf step (baseline)": ahf_step,
        "linear_acc_ned_m_s2, one sample as tuples": rotate,
        "SingleChannel.step": filter_step(SingleChannel, False),
        "DualChannel.step": filter_step(DualChannel, False),
        "DualChannel.step + GPS velocity": filter_step(DualChannel, True),
        "DualChannel.run + GPS velocity (batch, per sample)": filter_run,
    }
    times = {name: [] for name in cases}
    for _ in range(ROUNDS):  # interleaved: machine load hits every case alike
        for name, fn in cases.items():
            start = time.perf_counter()
            fn()
            times[name].append((time.perf_counter() - start) / n * 1e6)
    base = statistics.median(times["ahf step (baseline)"])
    print("# bench/bench_position.py output\n")
    print("Command: `/work/venv/bin/python bench/bench_position.py` (2-core shared machine; timing noisy).\n")
    print(f"python {platform.python_version()}, numpy {np.__version__}; simulated flight {SECONDS:.0f} s = {n} samples, "
          f"barometer 25 Hz, GPS 10 Hz; median of {ROUNDS} interleaved rounds\n")
    print("| case | µs/sample | × ahf step |\n|---|---:|---:|")
    for name, values in times.items():
        med = statistics.median(values)
        print(f"| {name} | {med:.2f} | {med / base:.2f} |")


if __name__ == "__main__":
    main()

"""Opening a PX4 ``.ulg`` with the app's estimators, against pyulog's bare parse, in one run.

    PYTHONPATH=. python bench/bench_ulog.py [--rounds R] [--logs DIR]

Per shared ``.ulg``: CPU seconds (``time.process_time``: the machine is shared) of ``pyulog.ULog(path)``
(the baseline: pyulog's parse and nothing else) and of ``load_session(path)`` with its default estimators
(``estimators_for``: what File > Open, ``export`` and ``evaluate`` run), their ratio, and ours split by
stage: ``parse`` (the ``ULog`` construction inside ``read_ulog``), ``tables`` (``logtables.ulog_tables``),
``estimators`` (every estimator's ``run``) and the rest (``product/aiding/other``: the topics' checks
and streams, the aiding stage's heading and position, the onboard and truth interpolation, the product).
The stages are timed by wrapping those names where ``read_ulog`` and ``log_session`` look them up.

Rounds interleave the baseline and ours on each file so that the machine's load falls on both alike;
medians of R rounds. One process, imports excluded from both (done before the first round), numba's
cache warm (a first open before the rounds loads every kernel).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from contextlib import contextmanager
from pathlib import Path

import pyulog

from groundstation.session_makers import flight_log_session as log_session_module
from groundstation.autopilot import ulog as ulog_module
from groundstation.session_makers.load import estimators_for, load_session

LOGS = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets" / "flightlogs"
STAGES = ("parse", "tables", "estimators")


class StageClock:
    """CPU seconds spent inside the wrapped names since ``reset``."""

    def __init__(self):
        self.spent = dict.fromkeys(STAGES, 0.0)

    def reset(self) -> None:
        self.spent = dict.fromkeys(STAGES, 0.0)

    def timed(self, stage, function):
        def wrapper(*args, **kwargs):
            start = time.process_time()
            try:
                return function(*args, **kwargs)
            finally:
                self.spent[stage] += time.process_time() - start
        return wrapper

    @contextmanager
    def installed(self):
        """The stages' names wrapped where the reader and the log session look them up."""
        saved = ulog_module.ULog, ulog_module.ulog_tables, log_session_module.create
        ulog_module.ULog = self.timed("parse", saved[0])
        ulog_module.ulog_tables = self.timed("tables", saved[1])

        def create(*args, **kwargs):
            estimator = saved[2](*args, **kwargs)
            estimator.run = self.timed("estimators", estimator.run)
            return estimator

        log_session_module.create = create
        try:
            yield self
        finally:
            ulog_module.ULog, ulog_module.ulog_tables, log_session_module.create = saved


def cpu_seconds(function) -> float:
    start = time.process_time()
    function()
    return time.process_time() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--logs", type=Path, default=LOGS)
    args = parser.parse_args()
    paths = sorted(args.logs.glob("*.ulg"))
    clock = StageClock()
    print(f"load average {os.getloadavg()[0]:.1f} at the start; {args.rounds} interleaved rounds; CPU seconds, medians")
    for path in paths:
        load_session(path)  # numba's kernels loaded, every import done
        print(f"{path.name}: estimators {', '.join(estimators_for(path))}")
    base = {p: [] for p in paths}
    ours = {p: [] for p in paths}
    stages = {p: {s: [] for s in (*STAGES, "other")} for p in paths}
    with clock.installed():
        for _ in range(args.rounds):
            for path in paths:
                base[path].append(cpu_seconds(lambda: pyulog.ULog(str(path))))
                clock.reset()
                total = cpu_seconds(lambda: load_session(path))
                ours[path].append(total)
                for stage in STAGES:
                    stages[path][stage].append(clock.spent[stage])
                stages[path]["other"].append(total - sum(clock.spent.values()))
    print()
    print("| file | pyulog.ULog (s) | load_session (s) | ratio | parse | tables | estimators | product/aiding/other |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for path in paths:
        b, o = statistics.median(base[path]), statistics.median(ours[path])
        split = " | ".join(f"{statistics.median(stages[path][s]):.3f}" for s in (*STAGES, "other"))
        print(f"| {path.name} | {b:.3f} | {o:.3f} | {o / b:.2f}x | {split} |")


if __name__ == "__main__":
    main()

"""The benchmarks' stopwatch (``bench/bench_first_frame.py``, ``bench/bench_first_data.py``) and the tests':
with ``GROUNDSTATION_FIRST_FRAME=1`` in the environment, the app (``ui/first_frame.py``) and ``record``
print a line ``<moment> <CPU s>`` at each moment they reach (``first paint``, ``first data``): the process's
CPU seconds, every thread's, since it started. At the first data they also print the estimators whose
compiled kernel was not there yet (``uncompiled at first data: ahf2,ukf``: running interpreted, or not yet
run; empty on a warm start)."""

from __future__ import annotations

import os
import time

ENV = "GROUNDSTATION_FIRST_FRAME"
UNCOMPILED = "uncompiled at first data:"


def wanted() -> bool:
    return bool(os.environ.get(ENV))


def note(moment: str) -> float:
    """Print ``moment`` with the process's CPU seconds now; returns them."""
    cpu_s = time.process_time()
    print(f"{moment} {cpu_s:.3f}", flush=True)
    return cpu_s


def note_uncompiled(names) -> None:
    print(f"{UNCOMPILED} {','.join(names)}", flush=True)

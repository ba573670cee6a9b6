"""The figures a session is summed up by, each computed by one function that every place showing it
calls: the window (the attitude title's "IMU at … Hz", the link panel's loss), the flight report, the
logbook's dataset, the CLI's totals and the workbook's Session sheet (tests/session/test_figures.py).

- ``rate_hz``: a stream's sample rate, the median of its positive time steps (gaps and repeated
  times do not move it; the IMU's is the session's "IMU rate");
- ``loss_pct``: frames lost as a share of the frames sent (received + lost);
- ``span_s``: the time from a stream's first row to its last (the sample rows': the session's duration).
"""

from __future__ import annotations

import math

import numpy as np


def rate_hz(time_s) -> float:
    """Median rate of the finite, increasing times ``time_s`` (s); NaN with no such step."""
    time_s = np.asarray(time_s, dtype=float)
    steps = np.diff(time_s[np.isfinite(time_s)])
    steps = steps[steps > 0]
    return float(1.0 / np.median(steps)) if len(steps) else math.nan


def loss_pct(received: int, lost: int) -> float:
    """Frames lost, % of those sent; NaN when none were."""
    return 100.0 * lost / (received + lost) if received + lost > 0 else math.nan


def span_s(time_s) -> float:
    """Last finite time minus the first; 0 with fewer than two."""
    time_s = np.asarray(time_s, dtype=float)
    finite = time_s[np.isfinite(time_s)]
    return float(finite[-1] - finite[0]) if len(finite) > 1 else 0.0

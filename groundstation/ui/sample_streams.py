"""Which sample stream carries the view, and at what rate; no Qt.

A session's samples come as raw IMU (``imu``: the host estimators) and as the aircraft's own estimate
(``onboard``). The firmware's "estimated" mode sends only the latter, and an autopilot on a slow link
(RAW_IMU at 2-4 Hz) sends the IMU too slowly for host filtering (``autopilot.imu_rate.too_slow``):
then the onboard estimate is the one to show as the attitude (issue 24, defects 3 and 5), the main curve of
the plots (issue 34), whose time they follow, and no fused position is shown. The link's lateness is measured against the same streams' own rate (defect 6).
"""

from __future__ import annotations

import math

from groundstation.autopilot.imu_rate import too_slow
from groundstation.session_parts.figures import rate_hz
from groundstation.session.view import ProductView
from groundstation.ui.series import GAP_S

RATE_ROWS = 20  # the newest rows a stream's rate is the median interval of
# The raw IMU stopped when the aircraft's estimate is this many of the IMU's own intervals ahead of it
# (or GAP_S, at the project's rates): between two samples of a 2 Hz RAW_IMU the attitude runs 0.5 s ahead.
STOPPED_INTERVALS = 3


def newest_time_s(table) -> float | None:
    last = table.tail(1)
    return float(last[0][table.columns.index("time_s")]) if len(last) else None


def newest_rate_hz(table) -> float:
    """The sample rate of the newest samples of ``table`` (``figures.rate_hz``); NaN with fewer than 3."""
    rows = table.tail(RATE_ROWS)
    return rate_hz(rows[:, table.columns.index("time_s")]) if len(rows) >= 3 else math.nan


def interval_s(table) -> float:
    """The sample interval of the newest samples of ``table`` (s); NaN when not known."""
    return 1.0 / newest_rate_hz(table)


def stream_interval_s(view: ProductView) -> float:
    """The sample interval of the stream that carries the view now (``headline``): NaN when unknown."""
    return interval_s(view.onboard if headline(view)[0] == "onboard" else view.imu)


def slow_imu_hz(view: ProductView) -> float | None:
    """The IMU's rate (of its newest samples) when it is too slow for host filtering; None when it is not, or
    is not known yet."""
    imu_hz = newest_rate_hz(view.imu)
    return imu_hz if too_slow(imu_hz) else None


def headline(view: ProductView) -> tuple[str, str]:
    """(estimate, why): the estimate to show as the attitude: the first host estimator (AHF2 in the app),
    or "onboard" with the reason, when the session has no host estimator, when the raw IMU stopped while
    the aircraft's estimate goes on ("estimated" mode), or when the IMU is too slow for host filtering."""
    filters = view.filters
    onboard_s = newest_time_s(view.onboard)
    if onboard_s is None:
        return (filters[0], "") if filters else ("onboard", "")
    if not filters:
        return "onboard", ""
    imu_s = newest_time_s(view.imu)
    imu_hz = newest_rate_hz(view.imu)
    stopped_after_s = STOPPED_INTERVALS / imu_hz if STOPPED_INTERVALS / imu_hz > GAP_S else GAP_S  # NaN: GAP_S
    if imu_s is None or onboard_s - imu_s > stopped_after_s:
        return "onboard", "no raw IMU"
    if too_slow(imu_hz):  # ``slow_imu_hz``'s rule on the rate just read (the redraw asks at every tick)
        return "onboard", f"IMU at {imu_hz:.1f} Hz"
    return filters[0], ""

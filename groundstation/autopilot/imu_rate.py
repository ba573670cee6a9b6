"""Whether an IMU is fast enough to filter on the host: the one rule the stream requester, the warnings, the
product and the window follow (no MAVLink here, so every reader of the rule can import it cheaply)."""

from __future__ import annotations

from collections import deque

import numpy as np

from groundstation.session_parts.figures import rate_hz

MIN_FILTER_RATE_HZ = 20.0  # below: the gyro is integrated over > 50 ms steps; host estimates are display only
IMU_RATE = "imu_rate"  # the ``about`` of a live slow-IMU warning event: a product names the whole session's rate instead


class ImuRateMonitor:
    """IMU rate from the autopilot's own timestamps (median interval of the last ``window`` samples)."""

    def __init__(self, window: int = 50):
        self._times_us: deque[int] = deque(maxlen=window)
        self._rate_hz: float | None = None  # of the samples held (None: to be taken again)

    def add(self, time_us: int) -> None:
        if not self._times_us or time_us > self._times_us[-1]:
            self._times_us.append(time_us)
            self._rate_hz = None

    @property
    def rate_hz(self) -> float:
        """Asked after every chunk the front-end is fed: the median is taken again only when a sample came."""
        if len(self._times_us) < 3:
            return float("nan")
        if self._rate_hz is None:
            self._rate_hz = rate_hz(np.array(self._times_us, dtype=float) / 1e6)
        return self._rate_hz

    @property
    def too_slow(self) -> bool:
        return too_slow(self.rate_hz)


def too_slow(rate_hz: float) -> bool:
    """Whether an IMU at ``rate_hz`` is too slow for host filtering: the one rule the requester, the warnings
    and the window (the onboard estimate as the attitude, no fused position) follow; NaN (no rate yet): not."""
    return rate_hz < MIN_FILTER_RATE_HZ


def slow_imu_note(rate_hz: float) -> str | None:
    """The message the window, the importer and evaluate show; None when the rate is fine."""
    if not too_slow(rate_hz):
        return None
    return (f"IMU at {rate_hz:.1f} Hz: too slow for host filtering (needs >= {MIN_FILTER_RATE_HZ:.0f} Hz); "
            "the host estimates are shown but mean little; compare with the onboard attitude instead")

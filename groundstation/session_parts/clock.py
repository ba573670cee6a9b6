"""Session time: one monotonic axis in seconds for a whole session, whatever the device clock does.

Frames carry the device's 32-bit microsecond clock; chunks carry the host's arrival time. Within a
*segment* the session time is the device time (exact, drift and all: ``dt`` between samples is the
device's), unwrapped across the 71.6-minute wrap; when the host waited longer than a wrap (a long
outage) the wrap count is taken from the host's wait.

A frame cannot arrive before it was sent. So over a segment, session time minus host time (the
*lead*) is largest for the frame that came with the least delay, and no frame's lead exceeds that
by more than clock drift allows. One that does arrived "before it was sent": the device clock went
back (a reboot, a brown-out: the forward reading of the step is nearly a whole wrap) or jumped
ahead (a re-plugged or re-synchronised board). That ends the segment: a ``device_reset`` (the device
time went back) or ``clock_jump`` event is reported with both clocks, and the new segment starts
where the host clock says that frame arrived (at the least delay seen), never before the last time
given. Late frames never trigger this (USB batching, a busy host, a replay's bunched chunks: all
make frames late, never early). A frame stamped up to ``BACK_TOLERANCE_US`` before the last one
(a sensor reporting late) gets the last time given, so the axis never goes back.

Not detected: a reset hidden in an outage longer than the uptime before it (the device time then
seems to have advanced less than the host's; frames look late, as a host stall makes them).
"""

from __future__ import annotations

import numpy as np

from firmware_protocol.decoder import BACK_TOLERANCE_US

JUMP_TOLERANCE_S = 0.25  # a frame may arrive this much "early" (sampling jitter, timestamp granularity)
DRIFT_TOLERANCE = 0.02  # plus this fraction of the device time elapsed (crystals ±50 ppm; RC oscillators ~1 %)
MIN_STEP_S = 1e-6  # a new segment starts at least this after the last time given
DISCONTINUITIES = ("device_reset", "clock_jump")  # the event kinds
_WRAP = 1 << 32


def _jumped(early_s, step_us):
    """A frame this much earlier than any before it, ``step_us`` after the last, cannot be on the same clock."""
    return early_s > JUMP_TOLERANCE_S + DRIFT_TOLERANCE * step_us * 1e-6


class SessionClock:
    """``place(t_host_ns, t_us)`` for each timestamped frame in stream order returns its session time.

    After each call ``event`` is the discontinuity that frame revealed (else None), ``segment``
    counts them, and ``device_us`` is the frame's device time unwrapped within its segment (so
    differences of it within a segment are exact integers).
    """

    def __init__(self) -> None:
        self.event: dict | None = None
        self.segment = 0
        self.device_us = 0
        self._origin_ns: int | None = None  # host time of the first frame: session time 0
        self._last_t32 = 0
        self._last_us = 0  # unwrapped device time of the latest frame
        self._last_host_ns = 0
        self._last_s = 0.0  # the last session time given
        self._segment_s = 0.0  # session time at the segment's first frame
        self._segment_us = 0  # unwrapped device time at the segment's first frame
        self._lead_s = 0.0  # the largest (session time - host time) in the segment

    def place(self, t_host_ns: int, t_us: int) -> float:
        self.event = None
        t32 = t_us & 0xFFFFFFFF
        if self._origin_ns is None:
            self._origin_ns = t_host_ns
            self._start(t_host_ns, t32, 0.0)
            return 0.0
        step = (t32 - self._last_t32) & 0xFFFFFFFF
        if step > _WRAP - BACK_TOLERANCE_US:  # a little before the last frame: a late sensor
            self.device_us = self._last_us - (_WRAP - step)
            return self._last_s
        waited_ns = t_host_ns - self._last_host_ns
        if waited_ns > (step + _WRAP // 2) * 1000:  # an outage longer than half a wrap: count the wraps
            step += _WRAP * round((waited_ns // 1000 - step) / _WRAP)
        device_us = self._last_us + step
        time_s = self._time_of(device_us)
        early_s = self._lead_of(time_s, t_host_ns) - self._lead_s
        if early_s > 0.0:  # delivered faster than any frame before it
            if _jumped(early_s, step):
                return self._discontinuity(t_host_ns, t32)
            self._lead_s += early_s
        self.device_us = self._last_us = device_us
        self._last_t32, self._last_host_ns, self._last_s = t32, t_host_ns, time_s
        return time_s

    def _time_of(self, device_us):
        """Session time of an unwrapped device time in the current segment (numbers or arrays)."""
        return self._segment_s + (device_us - self._segment_us) * 1e-6

    def _lead_of(self, time_s, t_host_ns):
        """Session time minus host time since the first frame (numbers or arrays)."""
        return time_s - (t_host_ns - self._origin_ns) * 1e-9

    def place_many(self, t_host_ns: np.ndarray, t_us: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[tuple[int, dict]]]:
        """``place`` for each frame of two int64 columns: (session times, ``device_us`` after each, and
        (index, event) for each discontinuity), exactly as ``place`` frame by frame.

        The common frame (a forward step, no outage, no discontinuity) is computed for whole blocks as
        arrays: its session time needs only the segment, and the lead over a block is the running maximum
        of session minus host time wherever adding the earliness back gives that value exactly (it does
        but for rounding in rare cases). The first frame of a block that is not common, or whose lead
        the running maximum would not give bit for bit, goes through ``place`` itself.
        """
        n = len(t_us)
        times, device = np.empty(n), np.empty(n, dtype=np.int64)
        events: list[tuple[int, dict]] = []
        i, block = 0, 64
        while i < n:
            if self._origin_ns is None:
                a = 0
            else:
                j = min(n, i + block)
                t32 = t_us[i:j] & 0xFFFFFFFF
                host = t_host_ns[i:j]
                step = (t32 - np.concatenate(([self._last_t32], t32[:-1]))) & 0xFFFFFFFF
                waited_ns = host - np.concatenate(([self._last_host_ns], host[:-1]))
                device_us = self._last_us + np.cumsum(step)
                time_s = self._time_of(device_us)
                lead = self._lead_of(time_s, host)
                lead_before = np.maximum.accumulate(np.concatenate(([self._lead_s], lead[:-1])))
                early_s = lead - lead_before
                raised = early_s > 0.0
                uncommon = (step > _WRAP - BACK_TOLERANCE_US) | (waited_ns > (step + _WRAP // 2) * 1000)
                uncommon |= raised & (_jumped(early_s, step) | (lead_before + early_s != lead))
                a = int(np.argmax(uncommon)) if uncommon.any() else j - i
                if a:
                    k = a - 1
                    times[i : i + a], device[i : i + a] = time_s[:a], device_us[:a]
                    self.device_us = self._last_us = int(device_us[k])
                    self._last_t32, self._last_host_ns, self._last_s = int(t32[k]), int(host[k]), float(time_s[k])
                    self._lead_s = float(max(lead_before[k], lead[k]))
                    self.event = None
                block = min(2 * block, 1 << 16) if a == j - i else 64
            i += a
            if i < n:  # the uncommon frame, through the rules one frame at a time
                times[i] = self.place(int(t_host_ns[i]), int(t_us[i]))
                device[i] = self.device_us
                if self.event is not None:
                    events.append((i, self.event))
                i += 1
        return times, device, events

    def _discontinuity(self, t_host_ns: int, t32: int) -> float:
        time_s = max(self._last_s + MIN_STEP_S, (t_host_ns - self._origin_ns) * 1e-9 + self._lead_s)
        self.event = {
            "kind": DISCONTINUITIES[0] if t32 < self._last_t32 else DISCONTINUITIES[1],
            "t_host_ns": t_host_ns,
            "device_time_us_before": self._last_t32,  # the device's 32-bit clock, as sent
            "device_time_us_after": t32,
            "session_time_before_s": self._last_s,
            "session_time_s": time_s,
            "host_elapsed_s": (t_host_ns - self._last_host_ns) * 1e-9,
        }
        self.segment += 1
        self._start(t_host_ns, t32, time_s)
        return time_s

    def _start(self, t_host_ns: int, t32: int, time_s: float) -> None:
        self.device_us = self._last_us = self._segment_us = self._last_t32 = t32
        self._last_host_ns = t_host_ns
        self._last_s = self._segment_s = time_s
        self._lead_s = time_s - (t_host_ns - self._origin_ns) * 1e-9

"""Link health: rates, losses and CRC failures per second, and the device-to-host clock.

Everything is computed from the host arrival time of each chunk (stamped at the I/O edge) and
the decoder's counters, so a replayed recording reproduces the live figures. Losses are the
decoder's, which counts none across a restart of the sender; the clock offset and latency start
over when the device clock does (``restart``).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from firmware_protocol import DecoderStats
from firmware_protocol.batch import CHUNK_COUNTERS
from groundstation.session_parts.table import Table

PER_SECOND_COLUMNS = ("t_s", "frames", "bytes", "crc_errors", "frames_lost", "bytes_skipped")
_COUNTERS = CHUNK_COUNTERS  # the decoder's counters read per second (the batch decode reports them per chunk)
LATENCY_WINDOW = 1000  # samples (10 s at 100 Hz): short enough that clock drift stays under 1 ms


def clock_figures(host_minus_device_ns: np.ndarray) -> dict[str, float]:
    """The clock offset and latency (p50, p99) of samples whose (host - device) time differences these are.

    The smallest difference is taken as the clock offset (the fastest delivery); each sample's
    latency is its difference minus that offset.
    """
    if not len(host_minus_device_ns):
        return {"clock_offset_s": float("nan"), "latency_p50_ms": float("nan"), "latency_p99_ms": float("nan")}
    offset = host_minus_device_ns.min()
    p50, p99 = np.percentile(host_minus_device_ns - offset, [50, 99]) / 1e6
    return {"clock_offset_s": offset / 1e9, "latency_p50_ms": float(p50), "latency_p99_ms": float(p99)}


class LinkStats:
    def __init__(self, new_table=Table) -> None:
        """``new_table(columns)``: the session's tables (a live one's are bounded)."""
        self.per_second = new_table(PER_SECOND_COLUMNS)
        self._start_ns: int | None = None
        self._second = 0
        self._at_second_start = (0,) * len(_COUNTERS)
        self.last_frame_ns: int | None = None
        self.last_chunk_ns: int | None = None
        self._host_minus_device_ns: deque[int] = deque(maxlen=LATENCY_WINDOW)

    def on_chunk(self, t_host_ns: int, stats: DecoderStats, new_frames: int) -> None:
        """After the decoder took a chunk that arrived at ``t_host_ns``."""
        if self._start_ns is None:
            self._start_ns = t_host_ns
        second = (t_host_ns - self._start_ns) // 1_000_000_000
        if second > self._second:  # close the second, then the empty ones up to this chunk's
            now = tuple(getattr(stats, c) for c in _COUNTERS)
            self.per_second.append((self._second, *(a - b for a, b in zip(now, self._at_second_start))))
            self._at_second_start = now
            # The first and the last empty second stand for all of them (a plot draws zero between
            # the two, the totals are the same): a jump in the clock, by years, adds two rows.
            empty = range(self._second + 1, second)
            for silent in sorted({empty[0], empty[-1]}) if empty else ():
                self.per_second.append((silent, *(0,) * len(_COUNTERS)))
            self._second = second
        self.last_chunk_ns = t_host_ns
        if new_frames:
            self.last_frame_ns = t_host_ns

    def on_sample(self, t_host_ns: int, device_time_us: int) -> None:
        self._host_minus_device_ns.append(t_host_ns - device_time_us * 1000)

    def restart(self) -> None:
        """The device clock restarted or jumped: offsets measured before it mean nothing after it."""
        self._host_minus_device_ns.clear()

    def clock(self) -> dict[str, float]:
        """Device-to-host clock offset and per-sample latency (p50, p99) over the last samples."""
        return clock_figures(np.array(self._host_minus_device_ns, dtype=float))

    def rates(self) -> dict[str, float]:
        """Frames and bytes in the last complete second."""
        if not len(self.per_second):
            return {"frames_per_s": float("nan"), "bytes_per_s": float("nan")}
        last = self.per_second.tail(1)[0]
        return {"frames_per_s": float(last[1]), "bytes_per_s": float(last[2])}

    def since_last_frame_s(self, now_ns: int) -> float:
        return float("inf") if self.last_frame_ns is None else (now_ns - self.last_frame_ns) / 1e9

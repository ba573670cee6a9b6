"""The one-line live summary of a running session, for the headless commands."""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from groundstation import quaternion
from groundstation.session.live import LiveSession


def summary_line(session: LiveSession) -> str:
    p = session.pipeline
    with session.lock:
        last = p.imu.tail(1)
        stats = p.decoder.stats
        rates = p.link.rates()
    if not len(last):
        return f"waiting for data from {session.source.description}…"
    row = dict(zip(p.imu.columns, last[0]))
    name = p.filters[0]
    _, pitch, roll = np.degrees(quaternion.to_euler_zyx(np.array([row[f"{name}_q{c}"] for c in "wxyz"])))
    fps = rates["frames_per_s"]
    fps_text = "-" if math.isnan(fps) else f"{fps:.0f}"
    return (f"t {row['time_s']:8.2f} s  {name} pitch {pitch:+6.1f}° roll {roll:+6.1f}°  "
            f"{fps_text} frames/s  lost {stats.frames_lost}  CRC errors {stats.crc_errors}")


def totals_line(session: LiveSession) -> str:
    """What the session decoded in all: the last line of ``replay`` and ``record`` (equal for a
    recording and its replay)."""
    p = session.pipeline
    with session.lock:
        stats = p.decoder.stats
        return (f"{len(p.imu)} IMU samples, {stats.frames} frames, {stats.frames_lost} lost, "
                f"{stats.crc_errors} CRC errors, {stats.bytes_skipped} bytes skipped")


def follow(session: LiveSession, stream=sys.stdout, interval_s: float = 0.25, until=None) -> None:
    """Rewrite the summary line until the session's reader stops (or ``until()`` is true)."""
    tty = stream.isatty()
    last_print = 0.0
    while session.running and not (until and until()):
        time.sleep(interval_s if tty else 0.05)
        now = time.monotonic()
        if tty:
            stream.write("\r" + summary_line(session) + "\033[K")
            stream.flush()
        elif now - last_print >= 5.0:  # a log, not an animation
            stream.write(summary_line(session) + "\n")
            last_print = now
    stream.write(("\r" if tty else "") + summary_line(session) + "\n")

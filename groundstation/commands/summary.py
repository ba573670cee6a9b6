"""The one-line live summary of a running session, for the headless commands."""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from groundstation import quaternion
from groundstation.session_parts.figures import loss_pct, rate_hz, span_s
from groundstation.session.view import Session


SILENT_AFTER_S = 1.0  # a live link with no frame for this long is said to be silent


def summary_line(session: Session) -> str:
    """A replay of a file with no link in it (a flight log, a dataset: ``view.link`` None) says no link figures."""
    p = session.view
    with session.lock:
        last = p.imu.tail(1)
        if p.link is None:
            counters, rates, silent_s = None, None, 0.0
        else:
            counters = p.counters()
            rates = p.link.rates()
            silent_s = p.link.since_last_frame_s(time.monotonic_ns())
    if not session.connected:
        return f"PORT GONE: {session.source.description}, reconnecting…"
    if not len(last):
        return f"waiting for data from {session.source.description}…"
    if not session.source.is_replay and silent_s > SILENT_AFTER_S:  # a replay's times are the recorded ones
        return f"NO DATA for {silent_s:.0f} s from {session.source.description} (radio out of range? aircraft off?)"
    row = dict(zip(p.imu.columns, last[0]))
    attitude = ""
    if p.filters:  # a log with the aircraft's estimate only has none of its own
        name = p.filters[0]
        _, pitch, roll = quaternion.euler_deg(np.array([row[f"{name}_q{c}"] for c in "wxyz"]))
        attitude = f"  {name} pitch {pitch:+6.1f}° roll {roll:+6.1f}°"
    if counters is None:
        return f"t {row['time_s']:8.2f} s{attitude}"
    fps = rates["frames_per_s"]
    fps_text = "-" if math.isnan(fps) else f"{fps:.0f}"
    return f"t {row['time_s']:8.2f} s{attitude}  {fps_text} frames/s  lost {counters['frames_lost']}  CRC errors {counters['crc_errors']}"


def totals_line(session: Session) -> str:
    """What the session decoded in all: the last line of ``replay`` and ``record`` (equal for a
    recording and its replay)."""
    p = session.view
    with session.lock:
        imu_s = p.imu.column("time_s")
        samples = f"{len(imu_s)} IMU samples at {rate_hz(imu_s):.1f} Hz" if len(imu_s) else f"{len(p.onboard)} onboard attitude samples, no IMU"
        samples += f" over {span_s(imu_s if len(imu_s) else p.onboard.column('time_s')):.1f} s"  # the session's duration
        if p.link is None:  # a flight log or a dataset: no link was decoded
            return samples
        c = p.counters()
        line = (f"{samples}, {c['frames']} frames, {c['frames_lost']} lost ({loss_pct(c['frames'], c['frames_lost']):.1f} %), "
                f"{c['crc_errors']} CRC errors, {c['bytes_skipped']} bytes skipped")
    ignored = getattr(session.source, "ignored", None)  # a UDP source locked to its sender
    return f"{line}; {ignored}" if ignored and ignored.datagrams else line


def follow(session: Session, stream=None, interval_s: float = 0.25, until=None) -> None:
    """Rewrite the summary line until the session's reader stops (or ``until()`` is true); on standard
    output unless ``stream`` says otherwise (looked up at the call: it may have been replaced since import)."""
    stream = stream or sys.stdout
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

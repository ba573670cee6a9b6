"""Several sessions on one time axis: the first session's (the window's), in its session seconds.

Where another session's time 0 (its first sample) falls on that axis, ``offset_s``:

- live beside live: on wall time. Both stamp their chunks with this host's monotonic clock, so each
  session's time 0 has a host time: the IMU sample delivered fastest, its arrival less its session time
  (the least delay, as ``link.clock_figures`` takes the clock offset; a board that buffered samples before
  the port opened started before its first chunk). Placed once a session has ``PLACE_AFTER_S`` of samples;
  without raw IMU samples (the firmware's "estimated" mode) its first chunk's arrival stands for its time 0.
- a file: from its start (its 0 at the axis' 0, as PlotJuggler lays two logs), revealed up to the first
  session's present (``reveal_along``): it plays along with the first session, live or played back
  (its pauses and seeks too), and is shown whole when no first session is there.
- live beside a file: from the axis' 0 as well; a file's time has no wall clock to meet.

No Qt here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # for the annotations only: the session's parts do not import the product
    from groundstation.session.view import Session


PLACE_AFTER_S = 1.0  # of samples before a live session is placed: its fastest delivery among them


def offset_s(first: Session, other: Session) -> float | None:
    """Seconds from the first session's time 0 to the other's; None until both can be placed."""
    if first.source.is_replay or other.source.is_replay:
        return 0.0
    zeros = [zero_host_ns(first), zero_host_ns(other)]
    return None if None in zeros else (zeros[1] - zeros[0]) / 1e9


def zero_host_ns(session: Session) -> float | None:
    """The host time (ns, monotonic) of a live session's time 0; None before ``PLACE_AFTER_S`` of samples."""
    view = session.view
    with session.lock:
        t0_ns = view.t0_host_ns
        # the two columns, not every row of every column (an hour's imu table of a file: 300 MB in float64)
        imu = (view.imu.column("time_s"), view.imu.column("host_time_s")) if len(view.imu) else None
        onboard_s = float(view.onboard.tail(1)[0, view.onboard.columns.index("time_s")]) if len(view.onboard) else None
    if imu is not None:
        time_s, host_s = imu
        return None if time_s[-1] < PLACE_AFTER_S else t0_ns + float(np.nanmin(host_s - time_s)) * 1e9
    return None if onboard_s is None or onboard_s < PLACE_AFTER_S else float(t0_ns)


def axis_now_s(first: Session) -> float | None:
    """The first session's present: a file's playback clock, a live session's newest sample (None before any)."""
    if first.seekable:
        return first.source.position_s
    ends = []
    with first.lock:
        for table in (first.view.imu, first.view.onboard):
            if len(table):
                ends.append(float(table.tail(1)[0, table.columns.index("time_s")]))
    return max(ends, default=None)


def reveal_along(first: Session | None, other) -> bool:
    """A file (``playback.RevealSession``) revealed up to the first session's present, or whole with no
    first session; True when its clock went back (the views that only add rows start over)."""
    now = axis_now_s(first) if first is not None else other.source.duration_s
    target = min(now or 0.0, other.source.duration_s)
    if target == other.source.position_s:
        return False
    return other.seek(target)

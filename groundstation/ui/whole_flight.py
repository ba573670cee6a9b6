"""A flight log is looked at whole (issue 34): a flyer opening a ``.tlog``, ``.bin`` or ``.ulg`` expects the
whole flight at once, as Mission Planner and Flight Review show it, not a 1x playback in a 30 s window.
The file is computed whole anyway (``session_makers.load``), so it opens with the playback clock at its end and
paused, every row revealed, in the "whole session" time window; Play (from the start: Home) still plays it.
A recording or a dataset CSV opens as before: played from its start in the window the user chose."""

from __future__ import annotations

import math
from pathlib import Path

from groundstation import formats

WHOLE_WINDOW = "whole session"  # the live view's time window that shows a session whole


def is_flight_log(path: Path | None) -> bool:
    """A file of a format with a flight-log reader (``formats.flight_logs``)."""
    return path is not None and formats.sniff(path) in formats.flight_logs()


def opening_playback(path: Path) -> dict:
    """How the playback of a file just computed starts (``RevealSession``'s keywords): a flight log at its
    end (the clock stops at the data's end) and paused; anything else from its start, playing."""
    return {"paused": True, "position_s": math.inf} if is_flight_log(path) else {}


def replayed_path(session) -> Path | None:
    """The file a session plays back, None for a live one."""
    return getattr(session.source, "path", None) if session is not None and session.source.is_replay else None

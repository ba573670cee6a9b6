"""A recording played back as a source: as fast as possible, or paced at 0.25x-64x real time.

Chunks keep their recorded arrival times, so the link statistics of a replay are those of the
flight; ``read`` paces against the wall clock. This feeds a recording through the live path (what
``open_session`` on a recording, the live-path benchmarks and tests do); the app and ``replay``
compute a file whole and play the result back instead (``session.playback``), seeking included.
"""

from __future__ import annotations

import threading
import time

from groundstation.errors import UserError
from groundstation.recording import Recording, open_recording
from groundstation.sources.base import Chunk, SourceClosed, SourceError, refuse_reopen, refuse_uplink

MIN_SPEED, MAX_SPEED = 0.25, 64.0  # the replay speeds, here and in the app's playback (session.playback)
IDLE_WAIT_S = 0.05


def check_speed(value: float) -> float:
    """``value``, a multiple of real time; ValueError when outside 0.25x-64x."""
    if not MIN_SPEED <= value <= MAX_SPEED:
        raise ValueError(f"replay speed must be between {MIN_SPEED:g}x and {MAX_SPEED:g}x, not {value:g}x")
    return value


class ReplaySource:
    is_replay = True
    can_reopen = False
    can_send = False  # a recording has no aircraft to command

    def __init__(self, recording: Recording, speed: float | None = None):
        """``speed`` None: as fast as possible; otherwise a multiple of real time in [0.25, 64]."""
        self.recording = recording
        self.description = f"replay of {recording.path.name}"
        self._times = recording.chunk_t_host_ns
        self._t0 = int(self._times[0]) if len(self._times) else 0
        self._index = 0
        self._lock = threading.Lock()
        self._anchor: tuple[float, int] | None = None  # (wall clock, recorded time) the pace is set from
        self.speed = speed

    @property
    def speed(self) -> float | None:
        return self._speed

    @speed.setter
    def speed(self, value: float | None) -> None:
        if value is not None:
            check_speed(value)
        with self._lock:
            self._speed = value
            self._anchor = None  # re-anchor: the new pace starts now, from where we are

    @property
    def duration_s(self) -> float:
        return (int(self._times[-1]) - self._t0) / 1e9 if len(self._times) else 0.0

    def read(self) -> Chunk | None:
        with self._lock:
            if self._index >= len(self._times):
                raise SourceClosed(self.description)
            if self._speed is None:
                return self._take()
            recorded = int(self._times[self._index])
            if self._anchor is None:
                self._anchor = (time.monotonic(), recorded)
            wall0, rec0 = self._anchor
            wait = wall0 + (recorded - rec0) / 1e9 / self._speed - time.monotonic()
            if wait <= 0:
                return self._take()
        time.sleep(min(wait, IDLE_WAIT_S))
        return None

    def _take(self) -> Chunk:
        t_host_ns, data = self.recording.chunk(self._index)
        self._index += 1
        return Chunk(t_host_ns, data)

    def write(self, data: bytes) -> None:
        refuse_uplink(self)

    def reopen(self) -> None:
        refuse_reopen(self)

    def close(self) -> None:
        with self._lock:
            self._index = len(self._times)


def open_replay(path, speed: float | None = 1.0) -> ReplaySource:
    """The recording at ``path`` as a source; UserError when it cannot be read, has no link data
    (an imported dataset: export it instead) or the speed is out of range."""
    recording = open_recording(path)  # RecordingError (a UserError) when nothing can be read
    if recording.chunk_count == 0:
        raise UserError(f"{recording.path.name}: no link data to replay (an imported dataset? export or evaluate it instead)")
    try:
        return ReplaySource(recording, speed)
    except ValueError as error:
        raise SourceError(str(error)) from None


def parse_speed(text: str) -> float | None:
    """``max`` (as fast as possible) or a multiple of real time."""
    return None if text.lower() == "max" else float(text)


def open_spec(spec) -> ReplaySource:
    """``FILE.gsrec[?speed=X]``: real time unless told (``speed=max``: as fast as possible)."""
    spec.check_options({"speed"})
    return open_replay(spec.target, spec.option("speed", parse_speed, 1.0))

"""A recording played back as a source: as fast as possible, or paced at 0.25x-64x real time.

Chunks keep their recorded arrival times, so the link statistics of a replay are those of the
flight. Pause, seek and step act on the position; ``read`` paces against the wall clock.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from groundstation.errors import UserError
from groundstation.recording import Recording, open_recording
from groundstation.sources.base import Chunk, SourceClosed, SourceError, refuse_reopen, refuse_uplink

MIN_SPEED, MAX_SPEED = 0.25, 64.0
IDLE_WAIT_S = 0.05


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
        self._paused = False
        self._anchor: tuple[float, int] | None = None  # (wall clock, recorded time) the pace is set from
        self.speed = speed

    @property
    def speed(self) -> float | None:
        return self._speed

    @speed.setter
    def speed(self, value: float | None) -> None:
        if value is not None and not MIN_SPEED <= value <= MAX_SPEED:
            raise ValueError(f"replay speed must be between {MIN_SPEED}x and {MAX_SPEED}x, not {value}x")
        with self._lock:
            self._speed = value
            self._anchor = None  # re-anchor: the new pace starts now, from where we are

    @property
    def duration_s(self) -> float:
        return (int(self._times[-1]) - self._t0) / 1e9 if len(self._times) else 0.0

    @property
    def position_s(self) -> float:
        """Recorded time of the next chunk, seconds from the first."""
        with self._lock:
            if self._index >= len(self._times):
                return self.duration_s
            return (int(self._times[self._index]) - self._t0) / 1e9

    @property
    def index(self) -> int:
        return self._index

    def pause(self, paused: bool = True) -> None:
        with self._lock:
            self._paused = paused
            self._anchor = None

    @property
    def paused(self) -> bool:
        return self._paused

    def seek(self, t_s: float) -> int:
        """Continue from the first chunk at or after ``t_s``; returns its index.

        The caller decides what seeking means for the estimates (a session re-runs its pipeline
        from the start up to here, since filters have memory).
        """
        with self._lock:
            self._index = int(np.searchsorted(self._times, self._t0 + int(t_s * 1e9)))
            self._anchor = None
            return self._index

    def step(self) -> Chunk | None:
        """The next chunk now, whatever the pace or pause (None at the end)."""
        with self._lock:
            return self._take()

    def read(self) -> Chunk | None:
        with self._lock:
            if self._index >= len(self._times):
                raise SourceClosed(self.description)
            if self._paused:
                wait = IDLE_WAIT_S
            elif self._speed is None:
                return self._take()
            else:
                recorded = int(self._times[self._index])
                if self._anchor is None:
                    self._anchor = (time.monotonic(), recorded)
                wall0, rec0 = self._anchor
                wait = wall0 + (recorded - rec0) / 1e9 / self._speed - time.monotonic()
                if wait <= 0:
                    return self._take()
        time.sleep(min(wait, IDLE_WAIT_S))
        return None

    def _take(self) -> Chunk | None:
        if self._index >= len(self._times):
            return None
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

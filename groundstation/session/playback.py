"""A whole computed session shown as if it were arriving: how the app and ``replay --speed`` play any file.

Opening a file computes the whole session once, ``load_session`` (a recording, a dataset CSV, a
.tlog, .bin or .ulg), in a worker thread with its progress (``Loading``). Playback then reveals the
rows up to a clock running at the chosen speed (0.25x-64x): pause, step and seek only move that
clock, so seeking anywhere in an hour is immediate, and a what-if (other estimators or settings) is
another ``load_session`` that keeps the position. The window reads a ``RevealSession`` as it reads a
``LiveSession`` (``view.Session``): ``view``'s tables (the rows up to the clock), events, link
figures, config and estimator settings; its source cannot send. No Qt here.
"""

from __future__ import annotations

import bisect
import threading
import time
from pathlib import Path

import numpy as np

from groundstation.session_parts.link import LATENCY_WINDOW, PER_SECOND_COLUMNS, clock_figures
from groundstation.session.product import LinkSummary, SessionData, event_time_s
from groundstation.sources.replay import check_speed

TOTALS = ("frames", "crc_errors", "frames_lost", "bytes_skipped")  # the decoder's counters a replay shows
PLAY_INTERVAL_S = 0.02  # how often a session started on its own (the CLI's) moves its clock


def rows_of(columns: list[np.ndarray]) -> np.ndarray | None:
    """The (N, k) array whose columns ``columns`` are, in order (what ``Table.to_dict`` hands out), so
    that rows are a slice of it and not a copy (a seek far into an hour reveals 10^5 rows at once);
    None when they are separate arrays."""
    base = columns[0].base if columns else None
    if not (isinstance(base, np.ndarray) and base.ndim == 2 and base.shape[1] == len(columns) and base.dtype == float):
        return None
    start, (row_step, column_step) = base.ctypes.data, base.strides
    for i, column in enumerate(columns):
        if column.base is not base or column.ctypes.data != start + i * column_step or column.strides != (row_step,) \
                or len(column) != len(base):
            return None
    return base


def _floats(values) -> np.ndarray:
    """A column as float64, but the product's float32 ones (``product.held_dtype``) as they are: read a row range
    at a time into float64 (``RevealedTable._rows``), never copied whole."""
    values = np.asarray(values)
    return values if values.dtype == np.float32 else values.astype(float, copy=False)


class RevealedTable:
    """One table of a computed session, up to the clock: ``len``, ``tail``, ``column``, ``array`` and
    ``to_dict`` as a ``Table`` gives them. A row shows once the clock reaches ``reveal_at`` (its time;
    rows out of order wait for the ones before them; a row with no time, such as a CONFIG frame
    before the first sample, shows from the start)."""

    def __init__(self, columns: dict[str, np.ndarray], reveal_at: np.ndarray | None = None):
        self.columns = tuple(columns)
        self._values = [_floats(v) for v in columns.values()]
        self._whole = rows_of(self._values)
        times = self._values[self.columns.index("time_s")] if reveal_at is None else np.asarray(reveal_at, dtype=float)
        self._reveal_at = np.maximum.accumulate(np.where(np.isnan(times), -np.inf, times)) if len(times) else times
        self.shown = 0

    def reveal(self, t_s: float) -> None:
        self.shown = int(np.searchsorted(self._reveal_at, t_s, side="right"))

    @property
    def reveal_times(self) -> np.ndarray:
        """When each row shows (non-decreasing)."""
        return self._reveal_at

    @property
    def last_s(self) -> float:
        """When the last row shows (-inf for no rows)."""
        return float(self._reveal_at[-1]) if len(self._reveal_at) else -np.inf

    def __len__(self) -> int:
        return self.shown

    def _rows(self, start: int, end: int) -> np.ndarray:
        if self._whole is not None:
            return self._whole[start:end]  # a view: readers only read
        out = np.empty((end - start, len(self.columns)))
        for i, values in enumerate(self._values):
            out[:, i] = values[start:end]
        return out

    def tail(self, rows: int) -> np.ndarray:
        return self._rows(max(self.shown - rows, 0), self.shown)

    def array(self) -> np.ndarray:
        return self._rows(0, self.shown)

    def column(self, name: str) -> np.ndarray:
        return self._values[self.columns.index(name)][: self.shown].copy()

    def to_dict(self) -> dict[str, np.ndarray]:
        return {name: values[: self.shown].copy() for name, values in zip(self.columns, self._values)}


class RevealedLink:
    """The link figures of a recording up to the clock: its seconds closed so far, the decoder's
    counters summed over them (the whole session's at the end), the latency of the last samples from
    their recorded arrival and device times (as the live session measured it)."""

    def __init__(self, summary: LinkSummary, imu: RevealedTable, frames: list[RevealedTable]):
        self._imu = imu
        t_s = np.asarray(summary.per_second["t_s"], dtype=float)
        self.per_second = RevealedTable({c: summary.per_second[c] for c in PER_SECOND_COLUMNS}, reveal_at=t_s + 1.0)
        self._sums = {c: np.cumsum(summary.per_second[c]) for c in TOTALS}
        self._totals = summary.counters
        self._frames = frames  # the tables whose newest row is the newest frame
        self.totals = dict.fromkeys(TOTALS, 0)
        self.last_chunk_ns: int | None = None
        self.last_frame_ns: int | None = None

    def reveal(self, t_s: float, ended: bool) -> None:
        shown = len(self.per_second)
        for name in TOTALS:
            self.totals[name] = int(self._totals[name] if ended else self._sums[name][shown - 1] if shown else 0)
        self.last_chunk_ns = int(t_s * 1e9)
        newest = [t.tail(1)[0, 0] for t in self._frames if len(t)]  # time_s comes first in every table
        self.last_frame_ns = int(max(newest) * 1e9) if newest else None

    def clock(self) -> dict[str, float]:
        columns = self._imu.columns
        rows = self._imu.tail(LATENCY_WINDOW)
        diffs = rows[:, columns.index("host_time_s")] * 1e9 - rows[:, columns.index("device_time_us")] * 1e3
        restarts = np.flatnonzero(np.isnan(diffs))  # a reboot's gap row: the offset starts over after it
        return clock_figures(diffs[restarts[-1] + 1 :] if len(restarts) else diffs)

    def rates(self) -> dict[str, float]:
        last = self.per_second.tail(1)
        return {"frames_per_s": float(last[0][1]), "bytes_per_s": float(last[0][2])} if len(last) else \
            {"frames_per_s": float("nan"), "bytes_per_s": float("nan")}

    def since_last_frame_s(self, now_ns: int) -> float:
        return float("inf") if self.last_frame_ns is None else (now_ns - self.last_frame_ns) / 1e9


class Revealed:
    """What the window reads of a session (``view.ProductView``), from a computed session up to the
    clock. ``link`` is None for a file with no link in it (a flight log, a dataset)."""

    def __init__(self, data: SessionData, uncompiled: tuple[str, ...] = ()):
        self.filters = data.filters
        self._uncompiled = uncompiled  # asked for, left out of ``data`` until compiled (``load.Loading``)
        self.catalogue = data.catalogue
        self.config = data.config
        self.parameters = data.parameters  # as last set: each change is also an event, revealed with the clock
        self.parameter_defaults = data.parameter_defaults
        self.t0_host_ns = None  # every event carries its session time
        self.protocol = data.protocol
        self._settings = data.settings_at_end
        self.tables = tables = {name: RevealedTable(columns) for name, columns in data.tables.items()}
        self.imu, self.onboard = tables["imu"], tables["onboard"]
        self.link = RevealedLink(data.link, self.imu, [self.imu, self.onboard]) if data.link is not None else None
        notes = [*data.damage, *(data.metadata[k] for k in ("imu_warning", "notes") if data.metadata.get(k))]
        timed = [{**{k: v for k, v in e.items() if k != "t_s"}, "session_time_s": event_time_s(e)}
                 for e in data.events]
        timed += [{"kind": "warning", "t_host_ns": 0, "session_time_s": 0.0, "message": note} for note in notes]
        self._events = sorted(timed, key=lambda e: e["session_time_s"])
        self._event_times = [e["session_time_s"] for e in self._events]
        self.events: list[dict] = []
        ends = [t.last_s for t in tables.values()] + self._event_times[-1:]
        self.end_s = max([0.0, *(t for t in ends if np.isfinite(t))])

    def reveal(self, t_s: float) -> None:
        for table in self.tables.values():
            table.reveal(t_s)
        shown = bisect.bisect_right(self._event_times, t_s)
        if shown != len(self.events):  # a new list only when it changes (the console reads it every few ticks)
            self.events = self._events[:shown]
        if self.link is not None:
            self.link.per_second.reveal(t_s)
            self.link.reveal(t_s, t_s >= self.end_s)

    def counters(self) -> dict[str, int]:
        """The decoder's totals up to the clock (none for a file with no link in it)."""
        return dict(self.link.totals) if self.link is not None else {}

    def settings(self) -> dict[str, dict[str, float]]:
        """The estimators' settings as computed (after any recorded change)."""
        return {name: dict(values) for name, values in self._settings.items()}

    def uncompiled(self) -> tuple[str, ...]:
        """The estimators asked for that the file was computed without, their kernels compiling (a first start)."""
        return self._uncompiled


class Playback:
    """The clock of a replay, in session seconds: it runs at ``speed`` while not paused, from 0 to
    ``duration_s``, where it stops; ``clock`` gives the wall-clock time in seconds. Also what the window
    asks a session's source: a file cannot send."""

    is_replay = True
    can_send = False
    can_reopen = False

    def __init__(self, path: Path, duration_s: float, speed: float = 1.0, paused: bool = False, position_s: float = 0.0,
                 clock=time.monotonic):
        self.path = Path(path)
        self._clock = clock
        self.description = f"replay of {self.path.name}"
        self.duration_s = duration_s
        self._position_s = min(max(position_s, 0.0), duration_s)
        self._paused = paused
        self._anchor: tuple[float, float] | None = None  # (wall clock, position) the running clock counts from
        self._speed = check_speed(speed)

    @property
    def speed(self) -> float:
        return self._speed

    @speed.setter
    def speed(self, value: float) -> None:
        check_speed(value)
        self.advance()
        self._speed = value
        self._anchor = None
        self.advance()  # the new pace counts from now

    @property
    def paused(self) -> bool:
        return self._paused

    def pause(self, paused: bool = True) -> None:
        self.advance()
        self._paused = paused
        self._anchor = None
        self.advance()  # playing again counts from now

    @property
    def position_s(self) -> float:
        """Where the clock stood at the last ``advance`` (or move)."""
        return self._position_s

    @property
    def ended(self) -> bool:
        return self._position_s >= self.duration_s

    def advance(self) -> float:
        """Move the clock to the wall-clock time now; returns the position."""
        now_s = self._clock()
        if self._paused or self.ended:
            self._anchor = None
        elif self._anchor is None:
            self._anchor = (now_s, self._position_s)
        else:
            wall0, position0 = self._anchor
            self._position_s = min(position0 + (now_s - wall0) * self._speed, self.duration_s)
        return self._position_s

    def move_to(self, t_s: float) -> None:
        self._position_s = min(max(t_s, 0.0), self.duration_s)
        self._anchor = None
        self.advance()  # playing on counts from now


class RevealSession:
    """``data`` (computed from ``path`` with ``setup``: the estimators and forced settings asked, None
    for the file's own) played back (``view.Session``). The window calls ``advance`` on its timer;
    ``seek`` says whether the clock went back, so that views which only ever add rows start over."""

    seekable = True
    heard_protocol = None  # a file is decoded as what it is

    def __init__(self, data: SessionData, path, setup: tuple = (None, None), *, speed: float = 1.0,
                 paused: bool = False, position_s: float = 0.0, uncompiled: tuple[str, ...] = ()):
        self.data = data
        self.setup = setup
        self.view = Revealed(data, uncompiled)
        self.source = Playback(path, self.view.end_s, speed, paused, position_s)
        self.lock = threading.Lock()  # the window's readers take it, as they do a live session's
        self.connected = True
        self.error: str | None = None
        self.recorder = None  # a replay is not re-recorded
        self.recording_path = None
        self._stop = threading.Event()
        self._player: threading.Thread | None = None
        self._reveal()

    def start(self) -> RevealSession:
        """Let the clock run by itself in a thread (the CLI's paced replay); the window moves it on its
        timer instead (``advance``), so only one thread ever moves it."""
        self._player = threading.Thread(target=self._play, name="groundstation-playback", daemon=True)
        self._player.start()
        return self

    def _play(self) -> None:
        while self.running and not self._stop.wait(PLAY_INTERVAL_S):
            self.advance()

    def stop(self) -> None:
        self._stop.set()
        if self._player is not None:
            self._player.join()
        self.source.pause(True)

    def __enter__(self) -> RevealSession:
        return self.start()

    def __exit__(self, *exc_info) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        """Until the clock reaches the end of the data (then the transport offers Replay)."""
        return not self.source.ended

    def _reveal(self) -> None:
        with self.lock:
            self.view.reveal(self.source.position_s)

    def advance(self) -> None:
        self.source.advance()
        self._reveal()

    @staticmethod
    def held_config() -> None:
        """Nothing: a file's CONFIGs were answered when it was computed (the answer recorded live, or
        ``--accept-config-changes``)."""
        return None

    def resolve_config(self, accept: bool) -> None:
        """Nothing is held in a file."""

    def file(self) -> tuple[Path, float]:
        """The file played and its length (s)."""
        return self.source.path, self.source.duration_s

    def seek(self, t_s: float) -> bool:
        """Move the clock to ``t_s``: immediate, nothing is recomputed. True when it moved back."""
        back = bool(t_s < self.source.position_s)
        self.source.move_to(t_s)
        self._reveal()
        return back

    def step(self) -> None:
        """One more IMU sample (the clock to the next sample's time)."""
        imu = self.view.imu
        if len(imu) < len(imu.reveal_times):
            self.source.move_to(float(imu.reveal_times[len(imu)]))
            self._reveal()

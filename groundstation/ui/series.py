"""The plotted quantities of a growing session table, kept as numpy arrays the plots slice.

Each tick takes only the rows added since the last one (``Table.tail``), converts them once
(quaternions to pitch, roll and heading in degrees, rad/s to °/s) and appends them. Only plotted
quantities are kept, as float32 (time float64). The last ``RECENT_S`` seconds stay at full
resolution, so windows up to 10 minutes are slices, not copies; older samples are kept as the minimum and maximum
of every ``BIN_ROWS`` (what peak downsampling would draw of them anyway), drawn as a second curve
(``older``). The history is bounded: past ``HISTORY_BINS`` bins, neighbouring bins are merged in
pairs (the minimum of their minima, the maximum of their maxima) and new bins take twice the rows,
so all bins keep one width and a series holds at most
``RECENT_S`` of samples and 2 x ``HISTORY_BINS`` points per quantity however long the flight, and a
4-hour flight still has a bin every 7 s or less: at least two per pixel of a whole-session plot
1000 pixels wide, whose peak downsampling draws each pixel's minimum and maximum, so it looks the same.

A live session's series reaches its size by its tenth minute and keeps it (issue 35): once the series' pace is
known the recent buffer grows at once to ``RECENT_S`` at that pace (and ``RECENT_MARGIN``), the history's
buffer is made for its bound and merged in place; buffers grow without writing their new rows (untouched
pages take no memory until samples fill them).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from groundstation import quaternion
from groundstation.session_parts.table import Table

INITIAL_ROWS = 8192
GAP_S = 0.25  # samples further apart than this mark a gap (port gone, radio lost): 25 at 100 Hz
GAP_INTERVALS = 4  # ... or than this many of the series' own intervals, if more: a 2 Hz GPS_RAW_INT is a line
PACE_ROWS = 20  # the newest intervals a series' own interval is the median of (all of a larger take's)
MIN_PACE_ROWS = 3  # fewer intervals known: no gap yet (the first of a 2 Hz series' is not one)
RECENT_S = 660.0  # kept at full resolution: the 10-minute window and a margin
BIN_ROWS = 10  # older samples: min and max of each 10 (0.1 s at 100 Hz)
HISTORY_BINS = 4096  # more, and the history's bins are merged in pairs
RECENT_MARGIN = 1.05  # the recent buffer holds this much more than RECENT_S: its oldest 5 % binned at a time
HISTORY_ROWS = 3 * HISTORY_BINS  # the history's buffer: its 2 x HISTORY_BINS points and a binning's more

Derive = Callable[[np.ndarray, tuple[str, ...]], dict[str, np.ndarray]]


class Columns:
    """A time column (float64) and named float32 columns, appended at the end, dropped at the front."""

    def __init__(self, rows: int = INITIAL_ROWS):
        self.count = 0
        self.time_s = np.empty(rows)
        self.values: dict[str, np.ndarray] = {}

    @property
    def capacity(self) -> int:
        return len(self.time_s)

    def append(self, time_s: np.ndarray, values: dict[str, np.ndarray], room: int = 0) -> None:
        """Add rows at the end; a buffer that must grow grows by half, or to ``room`` rows if more."""
        end = self.count + len(time_s)
        if end > self.capacity:
            size = max(self.capacity * 3 // 2, end, room)
            self.time_s = self._grown(self.time_s, size)
            self.values = {k: self._grown(v, size) for k, v in self.values.items()}
        self.time_s[self.count : end] = time_s
        for name, column in values.items():
            if name not in self.values:
                self.add(name)
            self.values[name][self.count : end] = column
        self.count = end

    def add(self, name: str) -> None:
        """A quantity of its own buffer, not in the rows so far (NaN)."""
        self.values[name] = np.empty(self.capacity, dtype=np.float32)
        self.values[name][: self.count] = np.nan

    def _grown(self, column: np.ndarray, size: int) -> np.ndarray:
        grown = np.empty(size, dtype=column.dtype)  # the rows after ``count`` unwritten: no memory until filled
        grown[: self.count] = column[: self.count]
        return grown

    def drop_front(self, rows: int) -> None:
        for column in (self.time_s, *self.values.values()):
            column[: self.count - rows] = column[rows : self.count]
        self.count -= rows

    def since(self, t_s: float) -> int:
        """Index of the first row at or after ``t_s``."""
        return int(np.searchsorted(self.time_s[: self.count], t_s))


def min_max_bins(first_s: np.ndarray, last_s: np.ndarray, lows: dict[str, np.ndarray], highs: dict[str, np.ndarray],
                 size: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Every ``size`` consecutive entries (each spanning ``first_s``..``last_s`` with values ``lows``..``highs``:
    samples, or bins already) as one bin: two points, (its first time, the minimum), (its last time, the
    maximum). The one rule for binning samples and for merging bins. An entry NaN in every quantity (a
    restart's gap row, or a bin holding one) keeps its bin NaN, so the older curve breaks there too; other NaN
    (a quantity missing in some rows) are left out of the minimum and maximum."""
    whole = len(first_s) // size * size
    restart = np.logical_and.reduce([np.isnan(c[:whole]) for c in lows.values()]).reshape(-1, size).any(axis=1)
    binned = {}
    for name in lows:
        pairs = np.column_stack([np.fmin.reduce(lows[name][:whole].reshape(-1, size), axis=1),
                                 np.fmax.reduce(highs[name][:whole].reshape(-1, size), axis=1)])
        pairs[restart] = np.nan
        binned[name] = pairs.ravel()
    times = np.column_stack([first_s[:whole].reshape(-1, size)[:, 0], last_s[:whole].reshape(-1, size)[:, -1]])
    return times.ravel(), binned


def per_pixel(t: np.ndarray, values: np.ndarray, left_s: float, pixel_s: float) -> np.ndarray:
    """Indices of the samples that draw what all of them draw on pixel columns ``pixel_s`` wide from
    ``left_s``: in each column its first and last sample (the lines to the neighbouring columns), its
    lowest and highest (its extent), in time order, and every NaN (a gap's break, which also splits its
    column). At most four samples a column, whatever the window's length."""
    if len(t) < 2 or not pixel_s > 0:
        return np.arange(len(t))
    column = np.floor((t - left_s) / pixel_s)
    gap = np.isnan(values)
    start = np.flatnonzero(np.concatenate(([True], (column[1:] != column[:-1]) | gap[1:] | gap[:-1])))
    run = np.repeat(np.arange(len(start)), np.diff(np.append(start, len(t))))
    chosen = [start, np.append(start[1:], len(t)) - 1]
    for reduce, fill in ((np.minimum, np.inf), (np.maximum, -np.inf)):
        filled = np.where(gap, fill, values)  # a NaN's run is itself: it is its own extreme
        hits = np.flatnonzero(filled == reduce.reduceat(filled, start)[run])
        chosen.append(hits[np.concatenate(([True], run[hits][1:] != run[hits][:-1]))])  # the first in each run
    return np.unique(np.concatenate(chosen))


class Series:
    """``derive(rows, columns)`` -> ``{name: 1-D array}``: the quantities of some new table rows."""

    def __init__(self, table: Table, derive: Derive):
        self.table = table
        self._derive = derive
        self.taken = 0  # table rows taken so far
        self.recent = Columns()
        self.bin_rows = BIN_ROWS  # samples per bin of the history: doubles as its bins are merged
        self.history = Columns(HISTORY_ROWS)  # two rows per bin of older samples: (first time, min), (last time, max)
        self.gaps: list[tuple[float, float]] = []  # (last sample before, first sample after), seconds
        self._intervals = np.empty(0)  # the newest intervals between samples (s): the series' own pace

    def take(self, lock) -> int:
        """Append the rows added since the last call; returns how many. ``lock`` keeps the
        table from growing between measuring it and slicing it."""
        with lock:
            new = len(self.table) - self.taken
            rows = self.table.tail(new) if new > 0 else None
        if rows is None:
            return 0
        time_s = rows[:, self.table.columns.index("time_s")]
        edges = time_s if self.end_s is None else np.concatenate(([self.end_s], time_s))
        steps = np.diff(edges)
        self._intervals = np.concatenate([self._intervals, steps[np.isfinite(steps)]])[-max(PACE_ROWS, len(steps)):]
        pace_s = float(np.median(self._intervals)) if len(self._intervals) >= MIN_PACE_ROWS else np.nan
        gap_s = np.inf if np.isnan(pace_s) else max(GAP_S, GAP_INTERVALS * pace_s)
        before = np.flatnonzero(steps > gap_s)  # the gaps: between edges[i] and edges[i + 1]
        self.gaps += [(float(edges[i]), float(edges[i + 1])) for i in before]
        values = self._derive(rows, self.table.columns)
        if len(before):  # a NaN row in the middle of each gap: no curve draws a line across it
            at = before if self.end_s is not None else before + 1  # the row of ``time_s`` after the gap
            mid_s = (edges[before] + edges[before + 1]) / 2
            time_s = np.insert(time_s, at, mid_s)
            values = {name: np.insert(column.astype(np.float32), at, np.nan) for name, column in values.items()}
        if self.recent.count + len(time_s) > self.recent.capacity:
            self._bin_old_rows()
        self.recent.append(time_s, values, room=int(RECENT_MARGIN * RECENT_S / pace_s) if pace_s > 0 else 0)
        for name in values.keys() - self.history.values.keys():  # its history's buffers from the start too
            self.history.add(name)
        self.taken += new
        return new

    def _bin_old_rows(self) -> None:
        """Move whole bins of rows older than ``RECENT_S`` into the history as min/max pairs."""
        r = self.recent
        size = self.bin_rows
        old = r.since(r.time_s[r.count - 1] - RECENT_S) // size * size
        if old == 0:
            return  # all recent: the buffer grows instead
        values = {name: column[:old] for name, column in r.values.items()}
        self.history.append(*min_max_bins(r.time_s[:old], r.time_s[:old], values, values, size))
        r.drop_front(old)
        h = self.history
        if h.count > 2 * HISTORY_BINS:
            whole = h.count // 4 * 4  # whole pairs of bins (two points each); an odd last bin stays as it is
            times, merged = min_max_bins(h.time_s[:whole:2], h.time_s[1:whole:2], {n: c[:whole:2] for n, c in h.values.items()},
                                         {n: c[1:whole:2] for n, c in h.values.items()}, 2)
            rest = {n: c[whole : h.count] for n, c in h.values.items()}
            rest_s = h.time_s[whole : h.count]
            h.count = 0  # written again from the front, in the same buffers (the merged bins are new arrays)
            h.append(np.concatenate([times, rest_s]), {n: np.concatenate([merged[n], rest[n]]) for n in merged})
            self.bin_rows = 2 * size

    def newest_s(self, lock) -> float | None:
        """Time of the table's newest row, taken or not (one row read): whether a redraw would show anything new."""
        with lock:
            last = self.table.tail(1)
        return float(last[0, self.table.columns.index("time_s")]) if len(last) else None

    @property
    def end_s(self) -> float | None:
        """Time of the newest sample."""
        return float(self.recent.time_s[self.recent.count - 1]) if self.recent.count else None

    @property
    def start_s(self) -> float | None:
        part = self.history if self.history.count else self.recent
        return float(part.time_s[0]) if part.count else None

    def has(self, quantity: str) -> bool:
        return quantity in self.recent.values

    def data(self, quantity: str, seconds: float | None) -> tuple[np.ndarray, np.ndarray]:
        """(time, values) of the full-resolution samples in the last ``seconds`` (None: all): views."""
        r = self.recent
        if not r.count:
            return np.empty(0), np.empty(0, dtype=np.float32)
        start = 0 if seconds is None else max(r.since(self.end_s - seconds) - 1, 0)  # from one row before the edge
        return r.time_s[start : r.count], r.values[quantity][start : r.count]

    def older(self, quantity: str, seconds: float | None) -> tuple[np.ndarray, np.ndarray]:
        """(time, min/max pairs) of the binned samples in the last ``seconds`` (None: all): views,
        which change only when rows are binned (every few minutes), so they are drawn as a curve of
        their own rather than copied together with the recent samples every frame."""
        h = self.history
        if not h.count or quantity not in h.values:
            return np.empty(0), np.empty(0, dtype=np.float32)
        start = 0 if seconds is None else max(h.since(self.end_s - seconds) - 1, 0)
        return h.time_s[start : h.count], h.values[quantity][start : h.count]

    def value_at(self, quantity: str, t_s: float) -> float | None:
        """The value at the sample (or history point) nearest ``t_s``."""
        part = self.recent if not self.history.count or t_s >= self.recent.time_s[0] else self.history
        if not part.count or quantity not in part.values:
            return None
        times = part.time_s[: part.count]
        i = int(np.clip(np.searchsorted(times, t_s), 1, part.count - 1)) if part.count > 1 else 0
        i = i - 1 if i and abs(times[i - 1] - t_s) < abs(times[i] - t_s) else i
        return float(part.values[quantity][i])

    def nbytes(self) -> int:
        return sum(c.time_s.nbytes + sum(v.nbytes for v in c.values.values()) for c in (self.recent, self.history))


def clock_series(series: dict[str, Series]) -> Series | None:
    """The sample series that carries the time axis: the raw IMU's, or the aircraft's own estimate's
    when its samples are newer (the firmware's "estimated" mode sends no raw IMU); None before any sample."""
    candidates = [s for s in (series.get("imu"), series.get("onboard")) if s is not None and s.end_s is not None]
    return max(candidates, key=lambda s: s.end_s, default=None)


def shared_gaps(series: dict[str, Series]) -> list[tuple[float, float]]:
    """The stretches in which neither sample series ("imu", "onboard") had a sample: a series that never
    had one leaves the other's gaps as they are."""
    spans = [s.gaps for s in (series.get("imu"), series.get("onboard")) if s is not None and s.end_s is not None]
    if not spans:
        return []
    shared = spans[0]
    for gaps in spans[1:]:
        shared = [(max(a0, b0), min(a1, b1)) for a0, a1 in shared for b0, b1 in gaps if max(a0, b0) < min(a1, b1)]
    return shared


def attitude_deg(prefix: str, q: np.ndarray) -> dict[str, np.ndarray]:
    """Pitch, roll and heading (the yaw as a compass reads it, 0..360°)."""
    yaw, pitch, roll = quaternion.euler_deg(q)
    return {f"{prefix}_pitch_deg": pitch, f"{prefix}_roll_deg": roll, f"{prefix}_heading_deg": quaternion.heading_deg(yaw)}


def imu_quantities(filters: tuple[str, ...]) -> Derive:
    """Pitch, roll and heading of every host estimator, the sensors in g and °/s, AHF's λ and e_a."""

    def derive(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        col = {name: rows[:, i] for i, name in enumerate(columns)}
        out = {}
        # All estimators' quaternions in one (rows, estimators, 4) array: one conversion per take, so
        # eight estimators cost about what three did (numpy's per-call overhead dominates a frame's few rows).
        index = [columns.index(f"{name}_q{c}") for name in filters for c in "wxyz"]
        q = rows[:, index].reshape(len(rows), len(filters), 4)
        yaw, pitch, roll = quaternion.euler_deg(q)
        yaw = quaternion.heading_deg(yaw)
        for i, name in enumerate(filters):
            out[f"{name}_pitch_deg"], out[f"{name}_roll_deg"], out[f"{name}_heading_deg"] = pitch[:, i], roll[:, i], yaw[:, i]
        for axis in "xyz":
            out[f"acc_{axis}_g"] = col[f"acc_{axis}_g"]
            out[f"gyr_{axis}_dps"] = np.degrees(col[f"gyr_{axis}_rad_s"])
        for diagnostic in ("lam", "e_a"):
            if f"ahf_{diagnostic}" in col:
                out[f"ahf_{diagnostic}"] = col[f"ahf_{diagnostic}"]
        return out

    return derive


def truth_quantities(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """A simulator's true attitude (the ``truth`` table of a SITL log) in degrees."""
    return attitude_deg("truth", rows[:, [columns.index(f"q{c}") for c in "wxyz"]])


def onboard_quantities(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The aircraft's own estimate (ATTITUDE frames) in degrees, and its λ."""
    col = {name: rows[:, i] for i, name in enumerate(columns)}
    out = attitude_deg("onboard", np.column_stack([col[f"q{c}"] for c in "wxyz"]))
    out["onboard_lam"] = col["lambda"]
    return out

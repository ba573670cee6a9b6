"""The plotted quantities of a growing session table, kept as numpy arrays the plots slice.

Each tick takes only the rows added since the last one (``Table.tail``), converts them once
(quaternions to pitch and roll in degrees, rad/s to °/s) and appends them to arrays grown by half
their size. A 10-minute or whole-session window is then a slice, not a copy of the table. Values
are float32 (plots need no more), time float64; only plotted quantities are kept (about 70 bytes
per sample with three estimators, against some 300 in the session's table).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from groundstation import quaternion
from groundstation.session.table import Table

INITIAL_ROWS = 8192
GAP_S = 0.25  # samples further apart than this mark a gap (port gone, radio lost): 25 at 100 Hz

Derive = Callable[[np.ndarray, tuple[str, ...]], dict[str, np.ndarray]]


class Series:
    """``derive(rows, columns)`` -> ``{name: 1-D array}``: the quantities of some new table rows."""

    def __init__(self, table: Table, derive: Derive):
        self.table = table
        self._derive = derive
        self.count = 0
        self.time_s = np.empty(INITIAL_ROWS)
        self.values: dict[str, np.ndarray] = {}
        self.gaps: list[tuple[float, float]] = []  # (last sample before, first sample after), seconds

    def take(self, lock) -> int:
        """Append the rows added since the last call; returns how many. ``lock`` keeps the
        table from growing between measuring it and slicing it."""
        with lock:
            new = len(self.table) - self.count
            rows = self.table.tail(new) if new > 0 else None
        if rows is None:
            return 0
        derived = self._derive(rows, self.table.columns)
        end = self.count + new
        if end > len(self.time_s):
            size = max(len(self.time_s) * 3 // 2, end)
            self.time_s = np.resize(self.time_s, size)
            self.values = {k: np.resize(v, size) for k, v in self.values.items()}
        self.time_s[self.count : end] = rows[:, self.table.columns.index("time_s")]
        times = self.time_s[max(self.count - 1, 0) : end]
        self.gaps += [(times[i], times[i + 1]) for i in np.flatnonzero(np.diff(times) > GAP_S)]
        for name, column in derived.items():
            if name not in self.values:
                self.values[name] = np.full(len(self.time_s), np.nan, dtype=np.float32)
            self.values[name][self.count : end] = column
        self.count = end
        return new

    def window(self, seconds: float | None) -> slice:
        """The rows of the last ``seconds`` of data (None: all)."""
        if seconds is None or self.count == 0:
            return slice(0, self.count)
        start = np.searchsorted(self.time_s[: self.count], self.time_s[self.count - 1] - seconds)
        return slice(max(int(start) - 1, 0), self.count)  # one row before: the curve reaches the edge

    def at(self, t_s: float) -> int | None:
        """Index of the row nearest ``t_s`` (None when empty)."""
        if self.count == 0:
            return None
        times = self.time_s[: self.count]
        i = int(np.clip(np.searchsorted(times, t_s), 1, self.count - 1)) if self.count > 1 else 0
        return i - 1 if i and abs(times[i - 1] - t_s) < abs(times[i] - t_s) else i


def pitch_roll_deg(prefix: str, q: np.ndarray) -> dict[str, np.ndarray]:
    _, pitch, roll = np.moveaxis(np.degrees(quaternion.to_euler_zyx(q)), -1, 0)
    return {f"{prefix}_pitch_deg": pitch, f"{prefix}_roll_deg": roll}


def imu_quantities(filters: tuple[str, ...]) -> Derive:
    """Pitch and roll of every host estimator, the sensors in g and °/s, AHF's λ and e_a."""

    def derive(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
        col = {name: rows[:, i] for i, name in enumerate(columns)}
        out = {}
        for name in filters:
            out.update(pitch_roll_deg(name, np.column_stack([col[f"{name}_q{c}"] for c in "wxyz"])))
        for axis in "xyz":
            out[f"acc_{axis}_g"] = col[f"acc_{axis}_g"]
            out[f"gyr_{axis}_dps"] = np.degrees(col[f"gyr_{axis}_rad_s"])
        for diagnostic in ("lam", "e_a"):
            if f"ahf_{diagnostic}" in col:
                out[f"ahf_{diagnostic}"] = col[f"ahf_{diagnostic}"]
        return out

    return derive


def onboard_quantities(rows: np.ndarray, columns: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The aircraft's own estimate (ATTITUDE frames) in degrees, and its λ."""
    col = {name: rows[:, i] for i, name in enumerate(columns)}
    out = pitch_roll_deg("onboard", np.column_stack([col[f"q{c}"] for c in "wxyz"]))
    out["onboard_lam"] = col["lambda"]
    return out

"""Another session's series on the window's time axis (``session.timeline``): its rows taken under its
own lock, its times moved by its offset. What the live view's Attitude tab and the Channels tab read of
the sessions added beside the window's own (``ui.session_list``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from groundstation.session.view import Session
from groundstation.ui.series import Derive, Series, imu_quantities, onboard_quantities

# Each added session's curves on the Attitude tab take a style of their own, in turn (the window's own
# are solid, its onboard estimate dashed); the estimators keep their colours.
SESSION_STYLES = ("dot", "dashdot", "dashdotdot")


@dataclass(frozen=True)
class Other:
    """A session beside the window's: ``label`` names its channels ("S2" -> "S2:imu.acc_x_g"), ``offset_s``
    places its time 0 on the window's axis, ``style`` is its curves' pen (``plots.PEN_STYLES``), ``shown``
    the estimators whose attitude and heading are plotted (with its onboard estimate)."""

    label: str
    session: Session
    offset_s: float
    style: str
    shown: tuple[str, ...]

    def name(self, table: str) -> str:
        return f"{self.label}:{table}"


class ShiftedTable:
    """``table``'s rows (``len``, ``tail``, ``columns``) with ``offset_s`` added to their time."""

    def __init__(self, table, offset_s: float):
        self._table = table
        self.columns = table.columns
        self._time = table.columns.index("time_s")
        self.offset_s = offset_s

    def __len__(self) -> int:
        return len(self._table)

    def tail(self, rows: int) -> np.ndarray:
        out = np.array(self._table.tail(rows), dtype=float)  # a copy: the table's own rows are only read
        out[:, self._time] += self.offset_s
        return out


class SessionSeries(Series):
    """A ``Series`` of a session's table (another's: a ``ShiftedTable``), taken under that session's lock,
    whichever the caller holds."""

    def __init__(self, table, derive: Derive, lock):
        super().__init__(table, derive)
        self._lock = lock

    def take(self, lock=None) -> int:
        return super().take(self._lock)


def other_series(others: list[Other]) -> dict[str, Series]:
    """The attitude series of each other session ("S2:imu", "S2:onboard"), as the live view has its own."""
    series = {}
    for other in others:
        view, lock = other.session.view, other.session.lock
        series[other.name("imu")] = SessionSeries(ShiftedTable(view.imu, other.offset_s), imu_quantities(view.filters), lock)
        series[other.name("onboard")] = SessionSeries(ShiftedTable(view.onboard, other.offset_s), onboard_quantities, lock)
    return series


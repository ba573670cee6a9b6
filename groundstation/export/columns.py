"""The exported columns of a session, the same for CSV, Parquet and Excel, read from its tables.

``time_s``; per estimator ``<name>_qw .. _qz`` (body to NED) and ``<name>_pitch_deg, _roll_deg,
_yaw_deg`` (ZYX, yaw ±180°: ``quaternion.euler_deg``, docs/conventions.md); ``onboard_*`` for the
aircraft's own estimate; the sensors in physical units; the truth quaternion when the session has
one; the magnetometer, barometer, GPS and fused-position readings when the session has them
(``aux_columns``). A name a log gave is one line of text (``text.clean``, visible), and two columns are never
one (``names.kept_apart``): a later one gets a suffix and a warning.
"""

from __future__ import annotations

import math

import numpy as np

from groundstation import quaternion
from groundstation.errors import UserError
from groundstation.names import kept_apart
from groundstation.session.product import SessionData
from groundstation.text import clean


def check_row_options(t_from: float | None, t_to: float | None, rate_hz: float | None) -> None:
    """UserError for a time range or rate no session can have (NaN, infinite, backwards, not positive)."""
    for option, value in (("--from", t_from), ("--to", t_to), ("--rate", rate_hz)):
        if value is not None and not math.isfinite(value):
            raise UserError(f"{option} must be a finite number, not {value}")
    if t_from is not None and t_to is not None and t_from > t_to:
        raise UserError(f"--from ({t_from} s) is after --to ({t_to} s)")
    if rate_hz is not None and rate_hz <= 0:
        raise UserError("--rate must be positive")


def select_rows(time_s: np.ndarray, t_from: float | None = None, t_to: float | None = None, rate_hz: float | None = None) -> np.ndarray:
    """Indices of the rows in [t_from, t_to], decimated to about ``rate_hz`` (every k-th sample)."""
    check_row_options(t_from, t_to, rate_hz)
    keep = np.ones(len(time_s), dtype=bool)
    if t_from is not None:
        keep &= time_s >= t_from
    if t_to is not None:
        keep &= time_s <= t_to
    rows = np.flatnonzero(keep)
    if len(rows) == 0:
        raise UserError(f"no samples between {t_from} s and {t_to} s (the session lasts {time_s[-1] if len(time_s) else 0:.1f} s)")
    if rate_hz is not None:
        # A table's rows can share a time or lack one (NaN): the period is that of the rows that have both.
        steps = np.diff(time_s)
        steps = steps[np.isfinite(steps) & (steps > 0)]
        period = float(np.median(steps)) if len(steps) else 1.0 / rate_hz
        step = max(1, int(round(1.0 / (rate_hz * period))))
        rows = rows[::step]
    return rows


def attitude_columns(prefix: str, q: np.ndarray) -> dict[str, np.ndarray]:
    yaw, pitch, roll = quaternion.euler_deg(q)
    out = {f"{prefix}_q{c}": q[:, i] for i, c in enumerate("wxyz")}
    out.update({f"{prefix}_pitch_deg": pitch, f"{prefix}_roll_deg": roll, f"{prefix}_yaw_deg": yaw})
    return out


def sensor_columns(data: SessionData) -> dict[str, np.ndarray]:
    """The ``imu`` table's sensors as exported: acceleration in g, rates in °/s, temperature; none for a
    session without IMU samples."""
    if data.sample_table != "imu":
        return {}
    imu = data.tables["imu"]
    out = {f"acc_{a}_g": imu[f"acc_{a}_g"] for a in "xyz"}
    out.update({f"gyr_{a}_dps": np.degrees(imu[f"gyr_{a}_rad_s"]) for a in "xyz"})
    out["temperature_c"] = imu["temperature_c"]
    return out


def export_columns(data: SessionData, rows: np.ndarray | None = None,
                   renamed: list[str] | None = None) -> dict[str, np.ndarray]:
    """``renamed``: told a warning per reading column renamed to keep it apart (``aux_columns``)."""
    rows = np.arange(len(data)) if rows is None else rows
    out = {"time_s": data.time_s[rows]}
    for name, q in data.attitudes(rows).items():
        out.update(attitude_columns(name, q))
    out.update({name: values[rows] for name, values in sensor_columns(data).items()})
    if data.true_q is not None:
        out.update({f"true_q{c}": data.true_q[rows, i] for i, c in enumerate("wxyz")})
    out.update(aux_columns(data, rows, tuple(out), renamed))
    return out


def aux_columns(data: SessionData, rows: np.ndarray, taken: tuple[str, ...] = (),
                renamed: list[str] | None = None) -> dict[str, np.ndarray]:
    """Every timestamped table but ``imu``/``onboard`` (``data.catalogue``: one per downlink frame, and
    the fused position), each column prefixed by its table's export prefix (``mag_``, ``baro_``,
    ``gps_``, ``fused_``, ...). Each reading sits on the row of the first IMU sample at or after it;
    the other rows are empty (NaN).

    The readings come at their own rates (e.g. GPS 10 Hz); empty cells show those rates, and any
    dropout, instead of hiding them behind repeated values. Where IMU frames were lost, two readings
    can share the next IMU row: the later one is kept. The Excel export's Sensors sheet lists every
    reading at its own time.

    Names: ``<prefix>_<column>`` as one line (``text.clean``), kept apart (``names.kept_apart``) from the
    columns ``taken`` before them and from each other (table ``foo`` column ``bar_baz`` and table ``foo_bar``
    column ``baz``: ``foo_bar_baz`` and ``foo_bar_baz__2``); ``renamed`` is told a warning for each renamed.
    """
    placed_columns = []
    for info in reading_tables(data):
        values = data.tables[info.name]
        at = np.searchsorted(data.time_s, values["time_s"])  # each reading's IMU row
        # ``rows`` ascend: each reading whose IMU row is exported, and that row's place among them
        place = np.searchsorted(rows, at)
        exported = place < len(rows)
        exported[exported] = rows[place[exported]] == at[exported]
        prefix = info.export_prefix
        for column in info.column_names[1:]:
            placed = np.full(len(rows), np.nan)
            placed[place[exported]] = values[column][exported]  # of two readings on one row, the later
            name = clean(column if column.startswith(prefix) else f"{prefix}_{column}", visible=True)
            placed_columns.append((name, f"{info.name}.{column}", placed))
    names, warnings = kept_apart([*taken, *(n for n, _, _ in placed_columns)], [*taken, *(o for _, o, _ in placed_columns)],
                                 "exported column")
    if renamed is not None:
        renamed += warnings
    return {name: placed for name, (_, _, placed) in zip(names[len(taken):], placed_columns)}


ROWS_PER_STRETCH = 65_536  # a Parquet row group; the exported columns in memory at once (~70 columns: ~37 MB)


def export_stretches(data: SessionData, rows: np.ndarray, rows_per_stretch: int = ROWS_PER_STRETCH,
                     renamed: list[str] | None = None):
    """``export_columns`` of consecutive stretches of ``rows``: what a writer holds at once does not grow
    with the session's length; ``renamed`` told the columns renamed (once: every stretch has the same names)."""
    for start in range(0, max(len(rows), 1), rows_per_stretch):
        yield export_columns(data, rows[start:start + rows_per_stretch], renamed if start == 0 else None)


def reading_tables(data: SessionData) -> list:
    """The catalogue's tables of readings at their own rates that this session has rows in."""
    if data.catalogue is None:
        return []
    return [info for info in data.catalogue if info.name not in ("imu", "onboard") and info.timestamped
            and len(data.tables.get(info.name, {}).get("time_s", ()))]

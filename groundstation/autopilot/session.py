"""A flight log as a ``SessionData``: the host estimators run over its IMU on the autopilot's clock,
the onboard estimate (and a simulator's truth) interpolated onto the IMU rows, the slower sensors on
the rows they arrived at, so export and evaluate treat it like any session.

- ``dt`` comes from the autopilot's timestamps (never a log's receive time).
- Magnetometer readings reach the estimators on the first IMU row at or after them (as in the live
  pipeline), and GPS velocity when it has all three NED components (GPS_RAW_INT has no vertical
  speed, so a tlog's GPS does not aid); single-antenna GPS gives no heading.
- The onboard attitude and truth are interpolated (normalised linear, shortest way) between the
  two samples around each IMU row, and NaN where those two are more than ``MAX_GAP_S`` apart or the
  row lies outside them.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from groundstation import formats
from groundstation.autopilot.flightlog import GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, Series
from groundstation.autopilot.streams import slow_imu_note
from groundstation.errors import UserError
from groundstation.estimation import create
from groundstation.estimation.evaluation import sample_periods_s
from groundstation.session.catalogue import Catalogue, message_table, session_catalogue
from groundstation.session.pipeline import DEFAULT_FILTERS
from groundstation.session.product import ONBOARD, SessionData, build_product, estimate_columns

MAX_GAP_S = 1.0
READ_SHARE = 0.3  # of a load's progress: reading the log; each estimator's run takes an equal part of the rest
PROGRESS_STEPS = 1000
# The log's slower sensors in the tables a live session fills with the same readings (the spec's
# MAG_RAW, BARO and GPS tables: one description, live and logged; a log has no compass heading column):
# stream -> (table, {column: (the stream's column, factor)}).
READINGS = {
    "mag": ("mag_raw", {c: (c, 1.0) for c in MAG_COLUMNS}),
    "baro": ("baro", {"pressure_Pa": ("pressure_hpa", 100.0), "temperature_degC": ("temperature_c", 1.0)}),
    "gps": ("gps", {c: (c, 1.0) for c in GPS_COLUMNS}),
}
AUTOPILOT_PROTOCOL = "mavlink"  # what the window treats a flight log's aircraft as speaking: no commands of ours


def load_log(path, filters=None, forced=None, progress=None) -> SessionData:
    """Read a ``.tlog``, ``.bin`` or ``.ulg`` and run ``filters`` (default: the pipeline's) with ``forced``
    settings; ``progress(done, total)`` through the reading, then after each estimator."""
    share = None if progress is None else lambda fraction: progress(round(PROGRESS_STEPS * fraction), PROGRESS_STEPS)
    reading = None if share is None else lambda done, total: share(READ_SHARE * min(done / max(total, 1), 1.0))
    return log_session(read_log(path, reading), filters or DEFAULT_FILTERS, forced or {}, share)


def read_log(path, progress=None) -> FlightLog:
    """The log at ``path`` by its format's reader (``formats``); UserError with a clear message when it cannot be read."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    file_format = formats.sniff(path)
    if file_format is None or file_format.read is None:
        raise UserError(f"{path}: not a flight log ({formats.described(formats.flight_logs())})")
    log = file_format.reader()(path, progress)
    if log.imu is None and log.onboard is None:
        found = f" ({'; '.join(log.notes)})" if log.notes else ""
        raise UserError(f"{path}: holds neither IMU samples nor an attitude estimate{found}; damaged or empty?")
    return log


def log_session(log: FlightLog, filters, forced: dict, share=None) -> SessionData:
    """``share(fraction)``: told after each estimator's run, from ``READ_SHARE`` to 1."""
    if log.imu is None:  # attitude only: the onboard estimate on its own rows
        t_us = log.onboard.time_us
        tables = {ONBOARD: onboard_columns(t_us, t_us[0], log.onboard.stack(Q_COLUMNS)), **reading_tables(log, t_us[0])}
        return build_product(describe(log), log_catalogue(log, {}), tables, (), protocol=AUTOPILOT_PROTOCOL,
                             true_q=interpolated(t_us, log.truth), true_frame="NED", damage=list(log.damage),
                             events=log_events(log, t_us[0]), parameters=dict(log.parameters))
    t_us = log.imu.time_us
    gyr, acc = log.imu.stack(IMU_COLUMNS[:3]), log.imu.stack(IMU_COLUMNS[3:])
    mag = on_rows(t_us, log.mag, MAG_COLUMNS)
    velocity = on_rows(t_us, log.gps, GPS_COLUMNS[3:6])
    velocity[~np.isfinite(velocity).all(axis=1)] = np.nan
    gps = np.column_stack([velocity, np.full(len(t_us), np.nan)])  # no heading from one antenna
    dt_s = sample_periods_s(t_us / 1e6)
    names, runs = list(dict.fromkeys(filters)), {}
    try:
        for i, name in enumerate(names, start=1):
            runs[name] = create(name, forced.get(name)).run(gyr, acc, dt_s, mag, gps)
            if share is not None:
                share(READ_SHARE + (1.0 - READ_SHARE) * i / len(names))
    except ValueError as error:
        raise UserError(str(error)) from None
    settings = {name: dataclasses.asdict(create(name, forced.get(name)).settings) for name in runs}
    imu = {"time_s": (t_us - t_us[0]) / 1e6, "device_time_us": t_us.astype(float), **log.imu.columns}
    for name, (q, diagnostics) in runs.items():
        imu.update(estimate_columns(name, q, diagnostics))
    tables = {"imu": imu, **reading_tables(log, t_us[0])}
    if log.onboard is not None:
        tables[ONBOARD] = onboard_columns(t_us, t_us[0], interpolated(t_us, log.onboard))
    catalogue = log_catalogue(log, {name: tuple(d) for name, (_, d) in runs.items()})
    return build_product(describe(log), catalogue, tables, tuple(runs), protocol=AUTOPILOT_PROTOCOL,
                         true_q=interpolated(t_us, log.truth), true_frame="NED",
                         settings_at_start=settings, settings_at_end=settings, damage=list(log.damage),
                         events=log_events(log, t_us[0]), parameters=dict(log.parameters))


def log_events(log: FlightLog, t0_us: int) -> list[dict]:
    """What the autopilot said (``FlightLog.events``) at session time: seconds from the first sample row
    (before it: negative), which is both the event's ``t_s`` and its place on the plots' axis."""
    return [{**event, "t_s": float(t_us - t0_us) / 1e6, "session_time_s": float(t_us - t0_us) / 1e6} for t_us, event in log.events]


def onboard_columns(t_us: np.ndarray, t0_us: int, q: np.ndarray) -> dict[str, np.ndarray]:
    """The ``onboard`` table of rows at ``t_us`` (λ and flags: a log has none)."""
    return {"time_s": (t_us - t0_us) / 1e6, "device_time_us": t_us.astype(float),
            **{c: q[:, i] for i, c in enumerate(Q_COLUMNS)}}


def reading_tables(log: FlightLog, t0_us: int) -> dict[str, dict[str, np.ndarray]]:
    """The slower sensors and every other logged message type (a tlog's VFR_HUD, SYS_STATUS, ...: "plot
    any channel"), each a table on its own rows in session time."""
    out = {}
    for key, (name, columns) in READINGS.items():
        stream: Series | None = getattr(log, key)
        if stream is not None:
            out[name] = {"time_s": (stream.time_us - t0_us) / 1e6,
                         **{c: stream.columns[source] * factor for c, (source, factor) in columns.items()}}
    for info, stream in _message_tables(log):
        out[info.name] = {"time_s": (stream.time_us - t0_us) / 1e6, **dict(zip(info.column_names[1:], stream.columns.values()))}
    return out


def log_catalogue(log: FlightLog, diagnostics: dict[str, tuple[str, ...]]) -> Catalogue:
    """The log's tables: ``imu`` with the estimators' columns, ``onboard`` and the slower sensors as the
    live session describes them; one per other message type, columns named ``<field>_<unit>`` from the
    log's units."""
    tables = session_catalogue(diagnostics)
    readings = [name for key, (name, _) in READINGS.items() if getattr(log, key) is not None]
    return Catalogue({name: tables[name] for name in ("imu", ONBOARD, *readings)} | {i.name: i for i, _ in _message_tables(log)})


def _message_tables(log: FlightLog) -> list[tuple]:
    """(``TableInfo``, ``Series``) of every other message type the log holds."""
    return [(message_table(name, f"{name} ({log.format})", list(stream.columns), log.units.get(name, {})), stream)
            for name, stream in log.tables.items()]


def describe(log: FlightLog) -> dict:
    """What the Session sheet and the commands show about the log."""
    meta = {"source": f"{formats.FORMATS[log.format].description} {log.path.name}", "autopilot": log.autopilot}
    for name in ("imu", "onboard", "mag", "baro", "gps", "truth"):
        stream: Series | None = getattr(log, name)
        if stream is not None:
            meta[f"{name} stream"] = f"{stream.source}, {len(stream)} samples at {stream.rate_hz:.1f} Hz"
    if log.imu is not None:
        meta["imu_rate_hz"] = round(log.imu.rate_hz, 2)
        note = slow_imu_note(log.imu.rate_hz)
        if note:
            meta["imu_warning"] = note
    if log.notes:
        meta["notes"] = "; ".join(log.notes)
    return meta


def on_rows(t_rows_us: np.ndarray, stream: Series | None, columns) -> np.ndarray:
    """(N, k) with each reading on the first row at or after it (the later one where two share a row),
    NaN on the other rows; all NaN when the log lacks the stream."""
    out = np.full((len(t_rows_us), len(columns)), np.nan)
    if stream is None:
        return out
    at = np.searchsorted(t_rows_us, stream.time_us)
    inside = at < len(t_rows_us)
    out[at[inside]] = stream.stack(columns)[inside]
    return out


def interpolated(t_rows_us: np.ndarray, stream: Series | None) -> np.ndarray | None:
    """Quaternions of ``stream`` at ``t_rows_us`` (normalised linear between neighbours; NaN across gaps)."""
    if stream is None:
        return None
    q = stream.stack(Q_COLUMNS)
    t = stream.time_us
    out = np.full((len(t_rows_us), 4), np.nan)
    after = np.searchsorted(t, t_rows_us)  # first sample at or after the row
    exact = (after < len(t)) & (t[np.minimum(after, len(t) - 1)] == t_rows_us)
    out[exact] = q[after[exact]]
    between = (after > 0) & (after < len(t)) & ~exact
    i1 = after[between]
    i0 = i1 - 1
    ok = (t[i1] - t[i0]) <= MAX_GAP_S * 1e6
    rows = np.flatnonzero(between)[ok]
    i0, i1 = i0[ok], i1[ok]
    a = ((t_rows_us[rows] - t[i0]) / (t[i1] - t[i0]))[:, None]
    q0, q1 = q[i0], q[i1]
    q1 = np.where((np.sum(q0 * q1, axis=1) < 0)[:, None], -q1, q1)  # the shorter way round
    blend = (1 - a) * q0 + a * q1
    out[rows] = blend / np.linalg.norm(blend, axis=1, keepdims=True)
    return out

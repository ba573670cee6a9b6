"""A flight log as a ``SessionData``: the host estimators run over its IMU on the autopilot's clock,
the onboard estimate (and a simulator's truth) interpolated onto the IMU rows, the slower sensors on
the rows they arrived at, so export and evaluate treat it like any session.

- ``dt`` comes from the autopilot's timestamps (never a log's receive time).
- Magnetometer, barometer and GPS readings go through the live session's aiding stage
  (``session_parts/aiding.py``), merged with the IMU samples by the autopilot's time: each reaches the
  estimators with the first IMU sample at or after it, GPS velocity when it has all three NED
  components (single-antenna GPS gives no heading); then the compass heading (``mag_raw``) and the
  fused position (``position``) on the aiding estimator's attitude, as live.
- Every other message type or topic is a table (``logtables``), the full-rate IMU too; ``imu="fast"``
  runs the estimators on that one (``fast_imu``) where it is a continuous stream (PX4's fifo topics). Where
  it is bursts with gaps between them (ArduPilot's batch sampler) the estimators stay on the logged IMU and
  the session says why (``burst_note``): an estimator must not integrate across the gaps, and the bursts with
  the logged IMU filling the gaps put AHF2 19° RMS in pitch from the autopilot on the shared CubeOrange log,
  where the logged IMU alone gives 2.9°.
- The onboard attitude and truth are interpolated (normalised linear, shortest way) between the
  two samples around each IMU row, and NaN where those two are more than ``MAX_GAP_S`` apart or the
  row lies outside them.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from groundstation import formats, quaternion
from groundstation.analysis.vibration import CONTINUOUS_SHARE, coverage, stretches
from groundstation.autopilot.flightlog import GPS_COLUMNS, IMU_COLUMNS, MAG_COLUMNS, Q_COLUMNS, FlightLog, Series, utc_text
from groundstation.autopilot.logtables import FAST, fast_name, held_dtypes
from groundstation.autopilot.imu_rate import slow_imu_note
from groundstation.errors import UserError
from groundstation.estimation import aiding_estimator, create
from groundstation.estimation.evaluation import sample_periods_s
from groundstation.session_parts import aiding
from groundstation.session_parts.catalogue import POSITION, TRUTH, Catalogue, estimator_columns, message_table, session_catalogue
from groundstation.session_makers.pipeline import DEFAULT_FILTERS
from groundstation.session.product import ONBOARD, SessionData, build_product, estimate_columns, held_dtype
from groundstation.formats import IMU_STREAMS
from groundstation.units import STANDARD_GRAVITY_M_S2

MAX_GAP_S = 1.0
FAST_IMU_FORMATS = ("dataflash", "ulog")  # the formats that can hold a full-rate IMU (``logtables``)
READ_SHARE = 0.3  # of a load's progress: reading the log; each estimator's run takes an equal part of the rest
PROGRESS_STEPS = 1000
# The log's slower sensors in the tables a live session fills with the same readings (the spec's
# MAG_RAW, BARO and GPS tables: one description, live and logged; the compass heading from the aiding stage):
# stream -> (table, {column: (the stream's column, factor)}).
READINGS = {
    "mag": ("mag_raw", {c: (c, 1.0) for c in MAG_COLUMNS}),
    "baro": ("baro", {"pressure_Pa": ("pressure_hpa", 100.0), "temperature_degC": ("temperature_c", 1.0)}),
    "gps": ("gps", {c: (c, 1.0) for c in GPS_COLUMNS}),
}
# A GPS reading as the aiding stage takes it (``Aiding.gps``) -> the log's GPS column
GPS_READING = {"lat": "lat_deg", "lon": "lon_deg", "alt": "alt_m", "vel_n": "vel_n_m_s", "vel_e": "vel_e_m_s",
               "vel_d": "vel_d_m_s", "fix_type": "fix_type"}
AUTOPILOT_PROTOCOL = "mavlink"  # what the window treats a flight log's aircraft as speaking: no commands of ours


def load_log(path, filters=None, forced=None, progress=None, imu: str = IMU_STREAMS[0]) -> SessionData:
    """Read a ``.tlog``, ``.bin`` or ``.ulg`` and run ``filters`` (default: the pipeline's) with ``forced``
    settings on its ``imu`` stream (``IMU_STREAMS``); ``progress(done, total)`` through the reading, then
    after each estimator."""
    share = None if progress is None else lambda fraction: progress(round(PROGRESS_STEPS * fraction), PROGRESS_STEPS)
    reading = None if share is None else lambda done, total: share(READ_SHARE * min(done / max(total, 1), 1.0))
    return log_session(read_log(path, reading), DEFAULT_FILTERS if filters is None else filters, forced or {}, share, imu)


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


def log_session(log: FlightLog, filters, forced: dict, share=None, imu: str = IMU_STREAMS[0]) -> SessionData:
    """``share(fraction)``: told after each estimator's run, from ``READ_SHARE`` to 1. The magnetometer,
    barometer and GPS go through the live session's aiding stage (``session_parts.aiding``) in time order with
    the IMU samples: the readings handed to the estimators, then the compass heading and the position on
    the aiding estimator's attitude."""
    notes = []
    if imu == "fast":
        note = burst_note(log)
        if note is None:
            log = dataclasses.replace(log, imu=fast_imu(log))
        else:
            notes.append(note)
    messages, renamed = _message_tables(log)
    log = dataclasses.replace(log, warnings=[*notes, *log.warnings, *renamed])
    if log.imu is None:  # attitude only: the onboard estimate on its own rows
        t_us = log.onboard.time_us
        tables = {ONBOARD: onboard_columns(t_us, t_us[0], log.onboard.stack(Q_COLUMNS)), **reading_tables(log, t_us[0], messages)}
        return build_product(describe(log, t_us[0]), log_catalogue(log, {}, messages), tables, (), protocol=AUTOPILOT_PROTOCOL,
                             true_q=interpolated(t_us, log.truth), true_frame="NED", damage=list(log.damage),
                             magnetometer=log.mag is not None, events=log_events(log, t_us[0]),
                             parameters=dict(log.parameters), parameter_defaults=dict(log.parameter_defaults))
    t_us = log.imu.time_us
    gyr, acc = log.imu.stack(IMU_COLUMNS[:3]), log.imu.stack(IMU_COLUMNS[3:])
    readings = _Readings(log, t_us)
    mag, gps = aiding.handed_to_samples(readings.stream, len(t_us), readings.mag_body, readings.gps_values)
    dt_s = sample_periods_s(t_us / 1e6)
    names, diagnostics, settings, estimates = list(dict.fromkeys(filters)), {}, {}, {}
    aiding_name, aiding_q = aiding_estimator(tuple(names)), None
    try:
        for i, name in enumerate(names, start=1):
            estimator = create(name, forced.get(name))
            q, diagnostics_of = estimator.run(gyr, acc, dt_s, mag, gps)
            # its columns in their held form at once (``held_dtype``): one estimator's float64 run at a time, not all
            diagnostics[name] = tuple(diagnostics_of)
            values = estimate_columns(name, q, diagnostics_of)
            estimates.update({c.name: np.asarray(values[c.name], dtype=held_dtype(c)) for c in estimator_columns(name, diagnostics[name])})
            aiding_q = q if name == aiding_name else aiding_q
            settings[name] = dataclasses.asdict(estimator.settings)  # frozen: what it ran with
            if share is not None:
                share(READ_SHARE + (1.0 - READ_SHARE) * i / len(names))
    except ValueError as error:
        raise UserError(str(error)) from None
    imu_table = {"time_s": (t_us - t_us[0]) / 1e6, "device_time_us": t_us.astype(float), **log.imu.columns, **estimates}
    tables = {"imu": imu_table, **reading_tables(log, t_us[0], messages)}
    heading, at, rows = aiding.heading_and_position(readings.stream, readings.mag_body, readings.pressure_pa,
                                                    readings.gps_values, aiding_q, acc, dt_s)
    if log.mag is not None:
        tables["mag_raw"]["heading_deg"] = heading
    if len(at):
        tables["position"] = {"time_s": tables["imu"]["time_s"][at], **dict(zip(POSITION.column_names[1:], rows.T))}
    if log.onboard is not None:
        tables[ONBOARD] = onboard_columns(t_us, t_us[0], interpolated(t_us, log.onboard))
    catalogue = log_catalogue(log, diagnostics, messages)
    return build_product(describe(log, t_us[0]), catalogue, tables, tuple(names), protocol=AUTOPILOT_PROTOCOL,
                         true_q=interpolated(t_us, log.truth), true_frame="NED", magnetometer=mag is not None,
                         settings_at_start=settings, settings_at_end=settings, damage=list(log.damage),
                         events=log_events(log, t_us[0]), parameters=dict(log.parameters), parameter_defaults=dict(log.parameter_defaults))


def log_events(log: FlightLog, t0_us: int) -> list[dict]:
    """The reader's warnings (``FlightLog.warnings``), then what the autopilot said (``FlightLog.events``) at
    session time: seconds from the first sample row (before it: negative), which is both the event's ``t_s``
    and its place on the plots' axis. The warnings are about the whole log: at its start (the first sample
    row, or the first event when one comes before it), so the events stay in time order."""
    said = [{**event, "t_s": float(t_us - t0_us) / 1e6, "session_time_s": float(t_us - t0_us) / 1e6} for t_us, event in log.events]
    start_s = min([0.0, *(e["t_s"] for e in said[:1])])
    return [{"kind": "warning", "message": w, "t_s": start_s, "session_time_s": start_s} for w in log.warnings] + said


class _Readings:
    """The log's magnetometer (body axes, µT), barometer (Pa) and GPS (the GPS frame's values, as the
    live front-end hands them: only a fix with all three velocity components aids) merged with the IMU
    samples by the autopilot's time; a reading at a sample's time comes before it (it reaches that sample)."""

    def __init__(self, log: FlightLog, t_us: np.ndarray):
        empty = np.zeros(0)
        self.mag_body = np.zeros((0, 3)) if log.mag is None else log.mag.stack(MAG_COLUMNS)
        self.pressure_pa = empty if log.baro is None else log.baro.columns["pressure_hpa"] * 100.0
        gps_t, self.gps_values = empty, {name: empty for name in (*GPS_READING, "heading")}
        if log.gps is not None:
            aids = np.isfinite(log.gps.stack(GPS_COLUMNS[3:6])).all(axis=1)
            gps_t = log.gps.time_us[aids]
            self.gps_values = {name: log.gps.columns[c][aids] for name, c in GPS_READING.items()}
            self.gps_values["heading"] = np.full(len(gps_t), math.nan)  # one antenna: no heading
        self.stream = aiding.merged([(empty if log.mag is None else log.mag.time_us, aiding.MAG),
                                     (empty if log.baro is None else log.baro.time_us, aiding.BARO),
                                     (gps_t, aiding.GPS), (t_us, aiding.SAMPLE)])


def burst_note(log: FlightLog) -> str | None:
    """None when the first IMU's full-rate gyro is a continuous stream the estimators can run on
    (``vibration.coverage`` at least ``CONTINUOUS_SHARE``); else why they stay on the logged IMU, in one line.
    UserError when the log has no full-rate gyro."""
    gyro = _fast_gyro(log)
    t_s = gyro.time_us / 1e6
    share = coverage(t_s)
    if share >= CONTINUOUS_SHARE:
        return None
    runs = stretches(t_s)
    samples = round(float(np.median([run.stop - run.start for run in runs])))
    logged = "the logged IMU" if log.imu is None else f"the logged IMU ({log.imu.source}, {log.imu.rate_hz:.0f} Hz)"
    return (f"the full-rate IMU ({gyro.source}) is logged in bursts, not a continuous stream ({len(runs)} "
            f"bursts of {samples} samples at {gyro.rate_hz:.0f} Hz, {share:.0%} of the time): the estimators stay on "
            f"{logged}; the bursts serve the vibration spectra and the what-if")


def _fast_gyro(log: FlightLog) -> Series:
    gyro = log.tables.get(fast_name("gyro", 0))
    if gyro is None:
        raise UserError(f"{log.path}: no full-rate IMU in this log (ArduPilot's ISBH/ISBD batch sampler, PX4's "
                        "sensor_gyro_fifo): open it with the regular IMU stream")
    return gyro


def fast_imu(log: FlightLog) -> Series:
    """The estimators' IMU stream at full rate (``--imu fast``, where ``burst_note`` finds it continuous): the
    first IMU's full-rate gyro samples (``logtables``), each with the accelerometer interpolated at its time
    from the full-rate accel where a stretch of it spans the sample, else from the logged IMU; before and
    after the full-rate gyro, the logged IMU's own samples. UserError when the log has no full-rate gyro."""
    gyro, accel = _fast_gyro(log), log.tables.get(fast_name("accel", 0))
    fast_us = np.asarray(gyro.time_us, dtype=float)
    regular_us = np.zeros(0) if log.imu is None else np.asarray(log.imu.time_us, dtype=float)
    between = ~_inside_stretches(regular_us, fast_us)
    t_us = np.concatenate([fast_us, regular_us[between]])
    gyr = np.concatenate([gyro.stack(FAST["gyro"][1]), log.imu.stack(IMU_COLUMNS[:3])[between] if log.imu else np.zeros((0, 3))])
    acc = np.full((len(t_us), 3), np.nan)
    if log.imu is not None:
        acc = np.column_stack([np.interp(t_us, regular_us, log.imu.columns[c]) for c in IMU_COLUMNS[3:]])
    if accel is not None:
        accel_us = np.asarray(accel.time_us, dtype=float)
        covered = _inside_stretches(t_us, accel_us)
        acc[covered] = np.column_stack([np.interp(t_us[covered], accel_us, accel.columns[c]) / STANDARD_GRAVITY_M_S2
                                        for c in FAST["accel"][1]])
    order = np.argsort(t_us, kind="stable")
    keep = np.isfinite(acc[order]).all(axis=1)
    t_us, gyr, acc = t_us[order][keep], gyr[order][keep], acc[order][keep]
    return Series(t_us, dict(zip(IMU_COLUMNS, np.column_stack([gyr, acc]).T)), f"{gyro.source} (full rate)")


def _inside_stretches(t_us: np.ndarray, burst_us: np.ndarray) -> np.ndarray:
    """Which of ``t_us`` lie within a gap-free stretch of ``burst_us`` (``vibration.stretches``: the one rule
    for where a stream has gaps), its ends included."""
    inside = np.zeros(len(t_us), dtype=bool)
    for run in stretches(burst_us):
        inside |= (t_us >= burst_us[run.start]) & (t_us <= burst_us[run.stop - 1])
    return inside


def onboard_columns(t_us: np.ndarray, t0_us: int, q: np.ndarray) -> dict[str, np.ndarray]:
    """The ``onboard`` table of rows at ``t_us`` (λ and flags: a log has none)."""
    return {"time_s": (t_us - t0_us) / 1e6, "device_time_us": t_us.astype(float),
            **{c: q[:, i] for i, c in enumerate(Q_COLUMNS)}}


def reading_tables(log: FlightLog, t0_us: int, messages: list[tuple]) -> dict[str, dict[str, np.ndarray]]:
    """The slower sensors, the truth, and every other table of the log (``messages``: each DataFlash message
    type or ULog topic, a tlog's VFR_HUD, SYS_STATUS, ...: "plot any channel"), each on its own rows in session time."""
    out = {}
    for key, (name, columns) in READINGS.items():
        stream: Series | None = getattr(log, key)
        if stream is not None:
            out[name] = {"time_s": (stream.time_us - t0_us) / 1e6,
                         **{c: stream.columns[source] * factor for c, (source, factor) in columns.items()}}
    if log.truth is not None:
        out[TRUTH.name] = {"time_s": (log.truth.time_us - t0_us) / 1e6, **log.truth.columns}
    for info, stream in messages:
        out[info.name] = {"time_s": (stream.time_us - t0_us) / 1e6, **dict(zip(info.column_names[1:], stream.columns.values()))}
    return out


def log_catalogue(log: FlightLog, diagnostics: dict[str, tuple[str, ...]], messages: list[tuple]) -> Catalogue:
    """The log's tables: ``imu`` with the estimators' columns (no host arrival time: a log has none),
    ``onboard``, the slower sensors and the position as the live session describes them, the truth; one
    per other message type or topic, columns named ``<field>_<unit>`` from the log's units."""
    tables = session_catalogue(diagnostics)
    imu = dataclasses.replace(tables["imu"], columns=tuple(c for c in tables["imu"].columns if c.name != "host_time_s"))
    readings = [name for key, (name, _) in READINGS.items() if getattr(log, key) is not None]
    aided = ["position"] if diagnostics and (log.baro is not None or log.gps is not None) else []
    truth = {TRUTH.name: TRUTH} if log.truth is not None else {}
    return Catalogue({"imu": imu} | {name: tables[name] for name in (ONBOARD, *readings, *aided)} | truth
                     | {i.name: i for i, _ in messages})


def _message_tables(log: FlightLog) -> tuple[list[tuple], list[str]]:
    """(``TableInfo``, ``Series``) of every other message type the log holds, each column held in its table's
    dtype (``logtables.logged_dtype``), and a warning for each column renamed to keep it apart (``message_table``)."""
    renamed = []
    return [(message_table(name, f"{stream.source} ({log.format})", list(stream.columns), log.units.get(name, {}), renamed,
                           held_dtypes(stream)), stream)
            for name, stream in log.tables.items()], renamed


def attach_simstate_truth(data: SessionData) -> None:
    """A SITL tlog's ``SIMSTATE`` (the simulator's attitude: ``roll``, ``pitch``, ``yaw`` in rad, ZYX body -> NED)
    as the session's truth: the ``truth`` table on its own rows, and ``true_q`` on the sample rows
    (interpolated as a log's truth is). Nothing without SIMSTATE."""
    sim = data.tables.get("simstate")
    if sim is None or not all(f"{a}_rad" in sim for a in ("roll", "pitch", "yaw")):
        return
    rows = np.isfinite(sim["time_s"]) & np.isfinite(sim["yaw_rad"])  # gap rows after a reboot have no time
    if not rows.any():
        return
    q = quaternion.from_euler_zyx(sim["yaw_rad"][rows], sim["pitch_rad"][rows], sim["roll_rad"][rows])
    data.catalogue = Catalogue({**data.catalogue.tables, TRUTH.name: TRUTH})
    data.tables[TRUTH.name] = {"time_s": sim["time_s"][rows], **dict(zip(Q_COLUMNS, q.T))}
    truth = Series(np.rint(sim["time_s"][rows] * 1e6), dict(zip(Q_COLUMNS, q.T)), "SIMSTATE")
    data.true_q, data.true_frame = interpolated(data.time_s * 1e6, truth), "NED"


def describe(log: FlightLog, t0_us: int) -> dict:
    """What the Session sheet and the commands show about the log; ``start_utc``, the UTC time of the
    session's start (its first row, at ``t0_us`` on the boot clock), where the log holds GPS or UTC time."""
    meta = {"source": f"{formats.FORMATS[log.format].description} {log.path.name}", "autopilot": log.autopilot}
    if log.utc_offset_us is not None:
        meta["start_utc"], meta["start_utc_source"] = utc_text(log.utc_offset_us + int(t0_us)), log.utc_source
    for name in ("imu", "onboard", "mag", "baro", "gps", "truth"):
        stream: Series | None = getattr(log, name)
        if stream is not None:
            meta[f"{name} stream"] = f"{stream.source}, {len(stream)} samples at {stream.rate_hz:.1f} Hz"
    if log.imu_choice:
        meta["imu_choice"] = log.imu_choice
    if log.imu is not None:
        meta["imu_rate_hz"] = round(log.imu.rate_hz, 2)
        note = slow_imu_note(log.imu.rate_hz)
        if note:
            meta["imu_warning"] = note
    if log.notes:
        meta["notes"] = "; ".join(log.notes)
    return meta


def interpolated(t_rows_us: np.ndarray, stream: Series | None) -> np.ndarray | None:
    """Quaternions of ``stream`` at ``t_rows_us`` (normalised linear between neighbours; NaN across gaps),
    ``INTERPOLATED_ROWS`` rows at a time: each row's value is its own, and what the arithmetic holds stays small
    beside the result (whole, it was six times the result's size)."""
    if stream is None:
        return None
    q = stream.stack(Q_COLUMNS)
    t = stream.time_us
    out = np.full((len(t_rows_us), 4), np.nan)
    for start in range(0, len(t_rows_us), INTERPOLATED_ROWS):
        _interpolate(t_rows_us[start:start + INTERPOLATED_ROWS], t, q, out[start:start + INTERPOLATED_ROWS])
    return out


INTERPOLATED_ROWS = 4096


def _interpolate(t_rows_us: np.ndarray, t: np.ndarray, q: np.ndarray, out: np.ndarray) -> None:
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

"""The batch path: a whole recording of the project's frames computed at once, as columns.

``batch_replay(recording)`` gives the same tables, events, link figures, config and settings as
``replay(recording)`` (the incremental ``Pipeline`` fed chunk by chunk; tests/session/test_batch.py
proves it), an order of magnitude faster: the byte stream is decoded into numpy columns per frame
type (``firmware_protocol.batch``), units and mounting are array operations, and every estimator
runs its batch ``run`` over the samples of each stretch between device restarts and settings changes.
Live data keeps the incremental path; a recording opened whole (``load_session``: export, evaluate,
the app) takes this one.

The pipeline's rules are not restated: its per-frame functions (``conversions``, ``in_body_axes``,
``sample_dt_s``, ``hold_expired``, ``gap_time_s`` ...) are called on arrays, and what is inherently
sequential and cheap runs the pipeline's own code over a column (``SessionClock`` over the frame
times, the rest-bias calibrator until it has measured, the compass heading per magnetometer frame).

Order. Everything the pipeline does happens at a frame (its position among the frames the decoder
returns) and, at one frame, in this order: recorded settings changes that apply before the chunk the
frame came with, then the clock's discontinuity (its event, the estimators' restart, the gap rows),
then the frame's handler. Each row and event gets that place as its key (``4 * frame + stage``),
so held IMU samples (waiting for a CONFIG) take the key of the frame that releases them. Readings
of the aiding sensors go to the first IMU sample processed after them, in the same device segment.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from firmware_protocol import SPEC
from firmware_protocol.batch import CHUNK_COUNTERS, BatchDecode, decode_batch
from firmware_protocol.decoder import DecoderStats
from groundstation import geodesy
from groundstation.estimation.compass import reading_heading_rad
from groundstation.position import linear_acc_ned_m_s2
from groundstation.recording import Recording
from groundstation.session.aiding import Aiding, gps_fix
from groundstation.session.catalogue import session_catalogue
from groundstation.session.clock import SessionClock
from groundstation.session.estimators import EstimatorBank
from groundstation.session.link import LinkStats
from groundstation.session.pipeline import (
    _LAMBDA_SCALE, _MAG_SCALES, _Q_SCALE, TEMPERATURE_SCALE, SensorConfig, conversions, gap_time_s, hold_expired,
    impossible_config_message, in_body_axes, no_config_message, period_s, sample_dt_s, schema_message, sensor_of,
)
from groundstation.session.replay import RecordedSetup, SettingsSchedule, apply_event, recorded_setup
from groundstation.session.table import Table

SETTINGS, DISCONTINUITY, HANDLER = 0, 1, 2  # the stages at one frame, in order
_FIX_2D = SPEC.enums["gps_fix"].values["fix_2d"]
# Shares of the whole job reported through ``progress``: reading and decoding, then the estimators.
_DECODE_SHARE = 0.4


class BatchSession:
    """What ``data.from_pipeline`` reads from a replayed ``Pipeline``, computed on the batch path."""

    def __init__(self, setup: RecordedSetup):
        self.bank = EstimatorBank(setup.filters, setup.settings, setup.forced, setup.aiding)
        self.filters = self.bank.filters
        self.catalogue = session_catalogue(self.bank.diagnostics(), SPEC)
        self.tables = {info.name: Table(info.column_names) for info in self.catalogue}
        self.imu, self.onboard = self.tables["imu"], self.tables["onboard"]
        self.link = LinkStats()
        self.config: dict | None = None
        self.sensor: SensorConfig | None = None
        self.events: list[dict] = []
        self.t0_host_ns: int | None = None
        self.decoder: BatchDecode | None = None  # ``decoder.stats``: the link's counters
        self._keyed_events: list[tuple[float, dict]] = [(-math.inf, e) for e in setup.warnings]
        self._key = math.inf  # where the settings change being applied happens (see _Builder)

    @property
    def estimators(self):
        return self.bank.estimators

    def settings(self) -> dict[str, dict[str, float]]:
        return self.bank.settings()

    def change_settings(self, name: str, overrides: dict[str, float], t_host_ns: int = 0) -> None:
        """As ``Pipeline.change_settings``; ``self._key`` says where in the session it happens."""
        self.bank.change(name, overrides)
        self.event(self._key, {"t_host_ns": t_host_ns, "kind": "settings", "name": name, "settings": dict(overrides)})

    def event(self, key: float, event: dict) -> None:
        self._keyed_events.append((key, event))


def batch_replay(recording: Recording, filters=None, forced=None,
                 progress: Callable[[int, int], None] | None = None) -> BatchSession:
    """``replay(recording, filters, forced)`` on the batch path (the project's own protocol only)."""
    setup = recorded_setup(recording, filters, forced)
    if setup.protocol != "gs":
        raise ValueError(f"the batch path decodes the project's frames, not {setup.protocol!r}")
    total = 1000

    def decoding(done: int, frames: int) -> None:
        if progress is not None:
            progress(int(_DECODE_SHARE * total * done / max(frames, 1)), total)

    def estimating(done: int, samples: int) -> None:
        if progress is not None:
            progress(int(total * (_DECODE_SHARE + (1 - _DECODE_SHARE) * done / max(samples, 1))), total)

    session = BatchSession(setup)
    decoded = decode_batch(*recording.stream(), progress=decoding)
    _Builder(session, decoded, SettingsSchedule(recording).changes(), estimating).build()
    if progress is not None:
        progress(total, total)
    return session


class _Builder:
    def __init__(self, session: BatchSession, decoded: BatchDecode, changes: list, progress):
        self.s, self.d, self.changes, self.progress = session, decoded, changes, progress
        self.rows: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {name: [] for name in session.tables}  # keys, rows

    def build(self) -> None:
        s, d = self.s, self.d
        s.decoder = d
        chunk_t = d.chunk_t_host_ns
        s.t0_host_ns = int(chunk_t[0]) if len(chunk_t) else None
        n = d.stats.frames
        self.chunk = np.zeros(n, dtype=np.int64)
        for columns in d.frames.values():
            self.chunk[columns.order] = columns.chunk
        self.t_host = chunk_t[self.chunk]
        self._clock(n)
        self._settings_keys()
        self._config()
        self._frame_tables()
        self._imu()
        self._gaps()
        self._link()
        for name in list(self.rows):
            parts = self.rows.pop(name)  # each table's rows are freed once in their table (memory: one copy at a time)
            if not parts:
                continue
            keys = np.concatenate([k for k, _ in parts]) if len(parts) > 1 else parts[0][0]
            rows = np.concatenate([r for _, r in parts]) if len(parts) > 1 else parts[0][1]
            del parts
            if (np.diff(keys) < 0).any():
                rows = rows[np.argsort(keys, kind="stable")]
            s.tables[name].extend(rows)
            del rows
        order = sorted(range(len(s._keyed_events)), key=lambda i: s._keyed_events[i][0])
        s.events = [s._keyed_events[i][1] for i in order]

    def key(self, positions) -> np.ndarray:
        return 4.0 * np.asarray(positions, dtype=float) + HANDLER

    def add(self, table: str, keys, rows) -> None:
        if len(keys):
            self.rows[table].append((np.asarray(keys, dtype=float), np.asarray(rows, dtype=float).reshape(len(keys), -1)))

    def segment(self, keys) -> np.ndarray:
        """How many discontinuities happened before each key."""
        return np.searchsorted(self.disc_keys, keys, side="right")

    # -- time -------------------------------------------------------------------------------------

    def _clock(self, n: int) -> None:
        """SessionClock over every timestamped frame in order; each frame's session and device time
        (a frame without timestamp: those of the last timestamped frame before it)."""
        timed_parts, time_parts = [], []
        for columns in self.d.frames.values():
            if columns.device_time_us is not None:
                timed_parts.append(columns.order)
                time_parts.append(columns.device_time_us)
        timed = np.concatenate(timed_parts) if timed_parts else np.zeros(0, dtype=np.int64)
        order = np.argsort(timed)
        timed = timed[order]
        device = np.concatenate(time_parts)[order] if time_parts else np.zeros(0, dtype=np.int64)
        times, unwrapped, events = SessionClock().place_many(self.t_host[timed], device)
        discontinuities = [(int(timed[i]), event) for i, event in events]
        last = np.searchsorted(timed, np.arange(n), side="right") - 1
        self.time_s = np.where(last >= 0, np.append(times, math.nan)[last], math.nan)
        self.device_us = np.where(last >= 0, np.append(unwrapped, 0)[last], 0)
        self.discontinuities = discontinuities
        self.disc_keys = np.array([4.0 * p + DISCONTINUITY for p, _ in discontinuities])
        for key, (_, event) in zip(self.disc_keys.tolist(), discontinuities):
            self.s.event(key, event)

    def _settings_keys(self) -> None:
        """Where each recorded settings change applies: before the first frame returned with a chunk
        that arrived after it (``SettingsSchedule.apply_before``)."""
        latest = np.maximum.accumulate(self.d.chunk_t_host_ns) if len(self.d.chunk_t_host_ns) else np.zeros(0)
        self.change_keys = []
        for t, event in self.changes:
            chunk = np.searchsorted(latest, t, side="right")
            frame = np.searchsorted(self.chunk, chunk)
            self.change_keys.append(4.0 * frame + SETTINGS if frame < len(self.chunk) else math.inf)

    # -- frames -----------------------------------------------------------------------------------

    def _values(self, name: str, k: int) -> dict:
        columns = self.d.frames[name]
        return dict(zip(columns.type.field_names, columns.raw[k].item()))

    def _config(self) -> None:
        """CONFIG frames (few): events, the sensor configuration from each, and what it says about the schema."""
        s, columns = self.s, self.d.frames["CONFIG"]
        self.sensor_keys: list[float] = []
        self.sensors: list[SensorConfig] = []
        fingerprints = columns.raw["schema_fingerprint"]
        for k, position in enumerate(columns.order.tolist()):
            key = 4.0 * position + HANDLER
            values = self._values("CONFIG", k)
            s.config = values
            t_host_ns = int(columns.t_host_ns[k])
            s.event(key, {"t_host_ns": t_host_ns, "kind": "config", **values})
            # The decoder had taken the whole chunk before the pipeline saw the frame: its last CONFIG.
            latest = fingerprints[np.searchsorted(columns.chunk, columns.chunk[k], side="right") - 1]
            if latest != SPEC.fingerprint:
                s.event(key, {"t_host_ns": t_host_ns, "kind": "warning", "message": schema_message(values["schema_fingerprint"])})
            try:
                sensor = sensor_of(values)
            except (KeyError, ValueError):
                s.event(key, {"t_host_ns": t_host_ns, "kind": "warning", "message": impossible_config_message(values)})
                continue
            self.sensor_keys.append(key)
            self.sensors.append(sensor)

    def _frame_tables(self) -> None:
        """Every frame with a table of its own: session time, then its values in physical units."""
        for frame_type in SPEC.frames:
            name = frame_type.name.lower()
            if name not in self.s.tables or frame_type.name in ("MAG_RAW", "IMU_RAW", "ATTITUDE"):
                continue
            columns = self.d.frames[frame_type.name]
            if not len(columns):
                continue
            fields = [f.name for f in frame_type.fields[1 if frame_type.has_timestamp else 0 :]]
            rows = np.column_stack([self.time_s[columns.order], *(columns.scaled(f) for f in fields)])
            self.add(name, self.key(columns.order), rows)
            if frame_type.name == "ACK":
                for k, position in enumerate(columns.order.tolist()):
                    self.s.event(4.0 * position + HANDLER, {"t_host_ns": int(columns.t_host_ns[k]), "kind": "ack",
                                                            **self._values("ACK", k)})
        board = self.d.frames["ATTITUDE"]
        if len(board):
            q = [board.raw[c].astype(float) * _Q_SCALE for c in ("q_w", "q_x", "q_y", "q_z")]
            self.add("onboard", self.key(board.order), np.column_stack([
                self.time_s[board.order], self.device_us[board.order], *q, board.raw["lambda_gain"] * _LAMBDA_SCALE,
                board.raw["flags"].astype(float)]))

    # -- IMU and estimators -----------------------------------------------------------------------

    def _imu(self) -> None:
        s, columns = self.s, self.d.frames["IMU_RAW"]
        positions = columns.order
        keys = self.key(positions)
        self._hold(columns, keys)
        released = np.isfinite(keys)
        keys, positions = keys[released], positions[released]
        raw = columns.raw[released]
        n = len(keys)
        sensor_index = self._sensor_at(keys)
        acc, gyr = np.empty((n, 3)), np.empty((n, 3))
        first_dt = np.empty(n)
        for i in np.unique(sensor_index).tolist():
            rows = sensor_index == i
            acc_m, gyr_m, _ = conversions(self.sensors[i])
            r = raw[rows]
            acc[rows] = np.column_stack(in_body_axes(acc_m, *(r[f].astype(float) for f in ("acc_x", "acc_y", "acc_z"))))
            gyr[rows] = np.column_stack(in_body_axes(gyr_m, *(r[f].astype(float) for f in ("gyr_x", "gyr_y", "gyr_z"))))
            first_dt[rows] = period_s(self.sensors[i])
        if self.sensors:
            s.sensor = self.sensors[-1]
        device_us = self.device_us[positions]
        segment = self.segment(keys)
        first = np.ones(n, dtype=bool)
        first[1:] = segment[1:] != segment[:-1]
        dt = np.where(first, first_dt, sample_dt_s(device_us, np.concatenate(([0], device_us[:-1]))))
        mag, gps = self._aiding_for_estimators(keys, segment)
        q, estimated = self._estimate(keys, gyr, acc, dt, mag, gps, self.t_host[positions])
        self.add("imu", keys, np.column_stack([self.time_s[positions], device_us, (self.t_host[positions] - s.t0_host_ns) * 1e-9,
                                               *acc.T, *gyr.T, raw["temperature"] * TEMPERATURE_SCALE, *estimated]))
        del estimated, mag, gps
        self._position(keys, segment, acc, dt, q, self.time_s[positions])
        self._magnetometer(keys, segment, q)

    def _hold(self, columns, keys: np.ndarray) -> None:
        """IMU samples before the first usable CONFIG wait for it, up to ``HOLD_FOR_CONFIG_US``; then the
        assumed sensor configuration applies. Sets the keys of held samples to where they are released
        (inf: never)."""
        first_config = self.sensor_keys[0] if self.sensor_keys else math.inf
        held = np.flatnonzero(keys < first_config)
        if not len(held):
            return
        times = self.time_s[columns.order[held]]
        expired = np.flatnonzero(hold_expired(times, times[0]))
        if len(expired):
            k = int(held[expired[0]])
            release = float(keys[k])
            assumed = SensorConfig()
            self.s.event(release, {"t_host_ns": int(columns.t_host_ns[k]), "kind": "warning", "message": no_config_message(assumed)})
            self.sensor_keys.insert(0, release)
            self.sensors.insert(0, assumed)
            keys[held[: expired[0] + 1]] = release
        else:
            keys[held] = first_config

    def _sensor_at(self, keys: np.ndarray) -> np.ndarray:
        return np.searchsorted(np.array(self.sensor_keys), keys, side="right") - 1

    def _readings(self, sample_keys, sample_segments, reading_keys) -> np.ndarray:
        """For each sample: the index of the last reading after the sample before it and before this one,
        in its device segment (the aiding stage hands each reading to the next sample); -1 for none."""
        if not len(reading_keys) or not len(sample_keys):
            return np.full(len(sample_keys), -1)
        last = np.searchsorted(reading_keys, sample_keys) - 1
        previous = np.concatenate(([-math.inf], sample_keys[:-1]))
        ok = last >= 0
        ok[ok] &= reading_keys[last[ok]] > previous[ok]
        ok[ok] &= self.segment(reading_keys[last[ok]]) == sample_segments[ok]
        return np.where(ok, last, -1)

    def _rows_at(self, values: np.ndarray, index: np.ndarray) -> np.ndarray | None:
        """``values`` (readings, width) at ``index`` (-1: a row of NaN); None when no sample has one."""
        if not (index >= 0).any():
            return None
        out = np.full((len(index), values.shape[1]), math.nan)
        out[index >= 0] = values[index[index >= 0]]
        return out

    def _mag_body(self) -> tuple[np.ndarray, np.ndarray]:
        """Magnetometer keys and readings in body axes (µT) with the mounting in effect at each frame."""
        columns = self.d.frames["MAG_RAW"]
        keys = self.key(columns.order)
        body = np.empty((len(keys), 3))
        sensor_index = self._sensor_at(keys)
        counts = [columns.raw[f].astype(float) for f in ("mag_x", "mag_y", "mag_z")]
        for i in np.unique(sensor_index).tolist():
            rows = sensor_index == i
            _, _, mag_m = conversions(self.sensors[i] if i >= 0 else SensorConfig())
            body[rows] = np.column_stack(in_body_axes(mag_m, *(c[rows] for c in counts)))
        return keys, body

    def _fixes(self):
        """GPS frames with at least a 2D fix (the others are ignored): keys, physical values by field."""
        columns = self.d.frames["GPS"]
        fixed = columns.raw["fix_type"] >= _FIX_2D
        values = {f.name: columns.scaled(f.name)[fixed] for f in columns.type.fields}
        return self.key(columns.order[fixed]), values

    def _aiding_for_estimators(self, keys, segment):
        mag_keys, mag_body = self._mag_body()
        mag = self._rows_at(mag_body, self._readings(keys, segment, mag_keys))
        gps_keys, values = self._fixes()
        fixes = np.array([gps_fix(dict(zip(values, row))) for row in zip(*values.values())]).reshape(-1, 4)
        gps = self._rows_at(fixes, self._readings(keys, segment, gps_keys))
        return mag, gps

    def _estimate(self, keys, gyr, acc, dt, mag, gps, t_host):
        """Every estimator over the samples, in stretches between restarts and settings changes; the
        rest-bias calibrator first. Returns the aiding estimator's quaternions and the table columns."""
        s, bank = self.s, self.s.bank
        n = len(keys)
        calibrator = bank.gyro_calibration
        measured_at = calibrator.measure(gyr, acc, dt)
        unbiased = gyr
        if measured_at is not None:
            bias = calibrator.bias_rad_s
            unbiased = gyr.copy()
            unbiased[measured_at:] = gyr[measured_at:] - np.array(bias)
            s.event(keys[measured_at], {"t_host_ns": int(t_host[measured_at]), "kind": "gyro_bias", "bias_rad_s": list(bias)})
        breaks = sorted([(k, 0, i) for i, k in enumerate(self.change_keys)] + [(k, 1, i) for i, k in enumerate(self.disc_keys.tolist())])
        outputs = {name: ([], []) for name in bank.filters}
        start = 0
        for key, kind, index in breaks + [(math.inf, 2, -1)]:
            end = int(np.searchsorted(keys, key))
            if end > start:
                for name, estimator in bank.estimators.items():
                    q, diag = estimator.run(gyr[start:end] if estimator.estimates_gyro_bias else unbiased[start:end],
                                            acc[start:end], dt[start:end], None if mag is None else mag[start:end],
                                            None if gps is None else gps[start:end])
                    outputs[name][0].append(q)
                    outputs[name][1].append(diag)
                    bank.last_q[name] = tuple(q[-1].tolist())
                self.progress(end, n)
                start = end
            if kind == 0:
                s._key = key
                apply_event(s, self.changes[index][1])
            elif kind == 1:
                bank.restart()
        columns, first_q = [], np.zeros((0, 4))
        for name in bank.filters:
            qs, diags = outputs[name]
            q = np.concatenate(qs) if qs else np.zeros((0, 4))
            if name == bank.aiding:
                first_q = q
            columns += list(q.T)
            for field in bank.diagnostics()[name]:
                columns.append(np.concatenate([d[field] for d in diags]).astype(float) if diags else np.zeros(0))
        return first_q, columns

    # -- aiding -----------------------------------------------------------------------------------

    def _position(self, keys, segment, acc, dt, first_q, time_s) -> None:
        """Seed 004's position from the first barometer or GPS reading on, on the aiding estimator's attitude."""
        if not self.s.filters:
            return
        baro = self.d.frames["BARO"]
        gps_keys, values = self._fixes()
        starts = [k for k in (self.key(baro.order[:1]).tolist() + gps_keys[:1].tolist())]
        if not starts:
            return
        on = keys > min(starts)
        keys, segment, acc, dt, q, time_s = keys[on], segment[on], acc[on], dt[on], first_q[on], time_s[on]
        if not len(keys):
            return
        pressure = baro.scaled("pressure")
        altitude = geodesy.pressure_altitude_m(pressure, float(pressure[0])) if len(pressure) else np.zeros(0)
        baro_alt = self._rows_at(altitude[:, None], self._readings(keys, segment, self.key(baro.order)))
        origin = (values["lat"][0], values["lon"][0], values["alt"][0]) if len(gps_keys) else None
        gps_index = self._readings(keys, segment, gps_keys)
        gps_pos = gps_vel = None
        if origin is not None:
            gps_pos = self._rows_at(geodesy.ned_from_geodetic(values["lat"], values["lon"], values["alt"], origin), gps_index)
            gps_vel = self._rows_at(np.column_stack([values["vel_n"], values["vel_e"], values["vel_d"]]), gps_index)
        acc_ned = linear_acc_ned_m_s2(acc, q)
        position = Aiding().position
        out = []
        for part in np.split(np.arange(len(keys)), np.flatnonzero(np.diff(segment)) + 1):
            position.reset()
            pos, vel = position.run(acc_ned[part], dt[part], None if baro_alt is None else baro_alt[part, 0],
                                    None if gps_pos is None else gps_pos[part], None if gps_vel is None else gps_vel[part])
            out.append(np.column_stack([pos, vel]))
        self.add("position", keys, np.column_stack([time_s, np.concatenate(out)]))

    def _magnetometer(self, keys, segment, first_q) -> None:
        """The magnetometer table, with the compass heading from the aiding estimator's latest attitude
        in the same device segment (NaN before it has one)."""
        columns = self.d.frames["MAG_RAW"]
        if not len(columns):
            return
        mag_keys, body = self._mag_body()
        latest = np.searchsorted(keys, mag_keys) - 1
        heading = np.full(len(mag_keys), math.nan)
        if self.s.filters and len(keys):
            ok = latest >= 0
            ok[ok] &= self.segment(keys[latest[ok]]) == self.segment(mag_keys[ok])
            qs = first_q[latest].tolist()
            heading_of = reading_heading_rad
            heading = np.array([math.degrees(heading_of(q, m)) if good else math.nan
                                for q, m, good in zip(qs, body.tolist(), ok.tolist())]).reshape(-1)
        shown = [columns.scaled(f) for f in ("mag_x", "mag_y", "mag_z")]
        self.add("mag_raw", mag_keys, np.column_stack([self.time_s[columns.order], *shown, heading]))

    # -- gaps and link ----------------------------------------------------------------------------

    def _gaps(self) -> None:
        """A row of NaN (but time) in every table that has rows when the device clock restarts or jumps."""
        for key, (_, event) in zip(self.disc_keys.tolist(), self.discontinuities):
            for name, parts in self.rows.items():
                if any((k < key).any() for k, _ in parts):
                    width = len(self.s.tables[name].columns)
                    parts.append((np.array([key]), np.array([[gap_time_s(event)] + [math.nan] * (width - 1)])))

    def _link(self) -> None:
        """``LinkStats.on_chunk`` at each chunk that starts a new second (the others change nothing kept)."""
        d, link = self.d, self.s.link
        times = d.chunk_t_host_ns
        if not len(times):
            return
        seconds = (times - times[0]) // 1_000_000_000
        new = np.ones(len(times), dtype=bool)
        new[1:] = seconds[1:] > np.maximum.accumulate(seconds)[:-1]
        counters = {name: d.chunk_counters[name] for name in CHUNK_COUNTERS}
        for c in np.flatnonzero(new).tolist():
            stats = DecoderStats(**{name: int(values[c]) for name, values in counters.items()})
            link.on_chunk(int(times[c]), stats, 0)

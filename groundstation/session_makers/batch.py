"""The batch path: a whole recording of the project's frames computed at once, as columns.

``batch_replay(recording)`` gives the same tables, events, link figures, config and settings as
``replay(recording)`` (the incremental ``Pipeline`` fed chunk by chunk; tests/session/test_batch.py
proves it), several times faster (bench/bench_batch.out.md): the byte stream is decoded into numpy
columns per frame type (``firmware_protocol.batch``), units and mounting are array operations, and
every estimator runs its batch ``run`` over the samples of each stretch between device restarts and
settings changes. Live data keeps the incremental path; a recording opened whole (``load_session``:
export, evaluate, the app) takes this one.

The pipeline's rules are not restated here. Its per-frame functions (``conversions``,
``in_body_axes``, ``sample_dt_s``, ``gap_row`` ...) are called on arrays, with the same operations in
the same order; what is sequential runs the pipeline's own code over the columns: ``SessionClock``
over the frame times, ``ConfigWait`` over the samples before the first CONFIG, the rest-bias
calibrator until it has measured, and the aiding stage (``Aiding``: readings handed to the samples,
compass heading, position) over the readings, samples and restarts merged in the pipeline's order
(``_Readings``). Scalar and vector maths never meet: NumPy's SIMD ``exp``/``log``/``pow`` may differ
from libm's in the last bit, so the same rule runs the same code on both paths.

Order. Everything the pipeline does happens at a frame (its position among the frames the decoder
returns), in the pipeline's order at one frame (``pipeline.stage_key``: recorded settings changes,
then the clock's discontinuity, then the frame's handler). Each row and event gets that place as its
key, so held IMU samples (waiting for a CONFIG) take the key of the frame that releases them.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from firmware_protocol import SPEC
from firmware_protocol.batch import CHUNK_COUNTERS, PIECE_BYTES, BatchDecode, decode_pieces, joined
from firmware_protocol.decoder import DecoderStats
from groundstation.estimation import settings_as_json
from groundstation.heap import give_back_freed_memory
from groundstation.recording import Recording
from groundstation.session_parts import aiding
from groundstation.session_parts.catalogue import IMU, estimator_columns, session_catalogue
from groundstation.session_parts.clock import SessionClock
from groundstation.session_makers.estimate_run import Break, EstimateRun, SampleColumns, SparseRows, Streamed
from groundstation.session_parts.estimators import EstimatorBank
from groundstation.session_parts.link import LinkStats
from groundstation.session_makers.pipeline import (
    ACC_FIELDS, DISCONTINUITY, GYR_FIELDS, HANDLER, LAMBDA_SCALE, MAG_FIELDS, Q_FIELDS, Q_SCALES, SETTINGS,
    TEMPERATURE_SCALE, ConfigGuard, ConfigWait, SensorConfig, conversions, gap_row, impossible_config_message, in_body_axes,
    period_s, sample_dt_s, sensor_of, stage_key, unexpected_frame_event,
)
from groundstation.session_makers.replay import CONFIG_ANSWERS, RecordedSetup, SettingsSchedule, apply_event, recorded_setup
from groundstation.session.product import estimate_columns, held_dtype
from groundstation.session_parts.table import Table

# Shares of the whole job reported through ``progress``: reading and decoding, then the estimators.
_DECODE_SHARE = 0.4


class BatchSession:
    """What ``load.from_pipeline`` reads from a replayed ``Pipeline``, computed on the batch path."""

    def __init__(self, setup: RecordedSetup, stream_estimates: bool = False):
        self.setup = setup
        self.bank = EstimatorBank(setup.filters, setup.settings, setup.forced, setup.aiding)
        # True: the estimators' imu columns (but the aiding one's) are not held, ``streamed`` makes them
        # for an export a stretch at a time (``estimate_run.Streamed``)
        self.stream_estimates = stream_estimates
        self.streamed: Streamed | None = None
        # The estimators' imu columns when held (not streamed): apart from the ``imu`` Table, in the product's form
        # (``product.held_dtype``), so an hour's are made at their held size, never float64 first
        self.held_estimates: dict[str, np.ndarray] = {}
        self.filters = self.bank.filters
        self.catalogue = session_catalogue(self.bank.diagnostics(), SPEC)
        self.tables = {info.name: Table(info.column_names) for info in self.catalogue}
        self.link = LinkStats()
        self.config: dict | None = None
        self.sensor: SensorConfig | None = None
        self.events: list[dict] = []
        self.parameters: dict[str, float] = {}  # the project's aircraft has none (an autopilot's: ``Pipeline``)
        self.unexpected_frames: dict[str, int] = {}
        self.t0_host_ns: int | None = None
        self.decoder: BatchDecode | None = None  # ``decoder.stats``: the link's counters
        self._keyed_events: list[tuple[float, dict]] = [(-math.inf, e) for e in setup.warnings]
        self._key = math.inf  # where the settings change being applied happens (see _Builder)

    imu = property(lambda self: self.tables["imu"])
    onboard = property(lambda self: self.tables["onboard"])

    @property
    def estimators(self):
        return self.bank.estimators

    def settings(self) -> dict[str, dict[str, float]]:
        return self.bank.settings()

    def change_settings(self, name: str, overrides: dict[str, float], t_host_ns: int = 0) -> None:
        """As ``Pipeline.change_settings``; ``self._key`` says where in the session it happens."""
        self.bank.change(name, overrides)
        self.event(self._key, {"t_host_ns": t_host_ns, "kind": "settings", "name": name, "settings": settings_as_json(overrides)})

    def event(self, key: float, event: dict) -> None:
        self._keyed_events.append((key, event))


def batch_replay(recording: Recording, filters=None, forced=None, progress: Callable[[int, int], None] | None = None,
                 accept_config_changes: bool = False, stream_estimates: bool = False,
                 piece_bytes: int | None = None) -> BatchSession:
    """``replay(recording, filters, forced, accept_config_changes=...)`` on the batch path (the project's own
    protocol only); ``stream_estimates``: ``BatchSession.stream_estimates``; ``piece_bytes``: the link's bytes
    decoded at a time (``firmware_protocol.batch.decode_pieces``: the same session whatever it is; None:
    ``PIECE_BYTES``)."""
    setup = recorded_setup(recording, filters, forced)
    if setup.protocol != "gs":
        raise ValueError(f"the batch path decodes the project's frames, not {setup.protocol!r}")
    total = 1000

    def decoding(pieces):
        chunks = 0
        for piece in pieces:
            chunks += len(piece.chunk_t_host_ns)
            if progress is not None:
                progress(int(_DECODE_SHARE * total * chunks / max(recording.chunk_count, 1)), total)
            yield piece

    def estimating(done: int, samples: int) -> None:
        if progress is not None:
            progress(int(total * (_DECODE_SHARE + (1 - _DECODE_SHARE) * done / max(samples, 1))), total)

    session = BatchSession(setup, stream_estimates)
    # A piece of the link's bytes at a time: the decode's own arrays are a piece's, not the recording's
    decoded = joined(decoding(decode_pieces(recording.pieces(piece_bytes or PIECE_BYTES))))
    give_back_freed_memory()  # the pieces'
    _Builder(session, decoded, SettingsSchedule(recording).changes(), estimating, ConfigGuard(accept_config_changes)).build()
    if progress is not None:
        progress(total, total)
    return session


class _Builder:
    def __init__(self, session: BatchSession, decoded: BatchDecode, changes: list, progress, guard: ConfigGuard):
        self.s, self.d, self.changes, self.progress, self.guard = session, decoded, changes, progress, guard
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
        self._unexpected()
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
            s.tables[name] = Table.holding(s.tables[name].columns, rows)
            del rows
        order = sorted(range(len(s._keyed_events)), key=lambda i: s._keyed_events[i][0])
        s.events = [s._keyed_events[i][1] for i in order]
        give_back_freed_memory()  # what made the tables

    def key(self, positions) -> np.ndarray:
        return stage_key(np.asarray(positions, dtype=float), HANDLER)

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
        is_timed = np.zeros(n, dtype=bool)
        device = np.zeros(n, dtype=np.int64)
        for columns in self.d.frames.values():
            if columns.device_time_us is not None:
                is_timed[columns.order] = True
                device[columns.order] = columns.device_time_us
        timed = np.flatnonzero(is_timed)
        times, unwrapped, events = SessionClock().place_many(self.t_host[timed], device[timed])
        discontinuities = [(int(timed[i]), event) for i, event in events]
        # Each frame's own times, written in place (memory: no session-long temporaries besides)
        self.time_s, self.device_us = np.full(n, math.nan), device
        self.time_s[timed], self.device_us[timed] = times, unwrapped
        untimed = np.flatnonzero(~is_timed)  # a few (CONFIG, ACK): the last timestamped frame's before them (NaN, 0: none)
        last = np.searchsorted(timed, untimed, side="right") - 1
        found = last >= 0
        self.time_s[untimed[found]], self.device_us[untimed[found]] = times[last[found]], unwrapped[last[found]]
        self.discontinuities = discontinuities
        self.disc_keys = np.array([stage_key(p, DISCONTINUITY) for p, _ in discontinuities])
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
            self.change_keys.append(stage_key(frame, SETTINGS) if frame < len(self.chunk) else math.inf)

    # -- frames -----------------------------------------------------------------------------------

    def _values(self, name: str, k: int) -> dict:
        columns = self.d.frames[name]
        return dict(zip(columns.type.field_names, columns.raw[k].item()))

    def _config(self) -> None:
        """CONFIG frames (few): events, the sensor configuration from each (``ConfigGuard``, told of the device
        restarts and the recorded answers to a held CONFIG in the pipeline's order), and what it says about
        the schema."""
        s, columns = self.s, self.d.frames["CONFIG"]
        self.sensor_keys: list[float] = []
        self.sensors: list[SensorConfig] = []
        fingerprints = columns.raw["schema_fingerprint"]
        steps = [(key, None) for key, (_, event) in zip(self.disc_keys.tolist(), self.discontinuities)
                 if event["kind"] == "device_reset"]
        steps += [(key, event) for key, (_, event) in zip(self.change_keys, self.changes) if event["kind"] in CONFIG_ANSWERS]
        steps += [(stage_key(position, HANDLER), k) for k, position in enumerate(columns.order.tolist())]
        for key, step in sorted(steps, key=lambda item: item[0]):
            if step is None:
                self.guard.device_reset()
                continue
            if isinstance(step, dict):
                sensor, event = self.guard.resolve(step.get("t_host_ns", 0), step["kind"] == CONFIG_ANSWERS[0])
                if event is not None:
                    s.event(key, event)
                if sensor is not None:
                    self.sensor_keys.append(key)
                    self.sensors.append(sensor)
                continue
            k = step
            values = self._values("CONFIG", k)
            s.config = values
            t_host_ns = int(columns.t_host_ns[k])
            s.event(key, {"t_host_ns": t_host_ns, "kind": "config", **values})
            # The decoder had taken the whole chunk before the pipeline saw the frame: its last CONFIG.
            latest = fingerprints[np.searchsorted(columns.chunk, columns.chunk[k], side="right") - 1]
            if (warning := SPEC.schema_warning(int(latest))) is not None:
                s.event(key, {"t_host_ns": t_host_ns, "kind": "warning", "message": warning})
            try:
                sensor = sensor_of(values)
            except (KeyError, ValueError):
                s.event(key, {"t_host_ns": t_host_ns, "kind": "warning", "message": impossible_config_message(values)})
                continue
            applies, event = self.guard.config(t_host_ns, sensor)
            if event is not None:
                s.event(key, event)
            if not applies:
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
                    self.s.event(stage_key(position, HANDLER), {"t_host_ns": int(columns.t_host_ns[k]), "kind": "ack",
                                                            **self._values("ACK", k)})
        board = self.d.frames["ATTITUDE"]
        if len(board):
            q = [board.raw[c].astype(float) * scale for c, scale in zip(Q_FIELDS, Q_SCALES)]
            self.add("onboard", self.key(board.order), np.column_stack([
                self.time_s[board.order], self.device_us[board.order], *q, board.raw["lambda_gain"] * LAMBDA_SCALE,
                board.raw["flags"].astype(float)]))

    def _unexpected(self) -> None:
        """Frames of uplink types (the aircraft never sends one): counted, the first of each type said."""
        for frame_type in SPEC.frames:
            columns = self.d.frames[frame_type.name]
            if frame_type.direction == "down" or not len(columns):
                continue
            self.s.unexpected_frames[frame_type.name] = len(columns)
            self.s.event(stage_key(int(columns.order[0]), HANDLER), unexpected_frame_event(int(columns.t_host_ns[0]), frame_type.name))

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
            acc[rows] = np.column_stack(in_body_axes(acc_m, *(r[f].astype(float) for f in ACC_FIELDS)))
            gyr[rows] = np.column_stack(in_body_axes(gyr_m, *(r[f].astype(float) for f in GYR_FIELDS)))
            first_dt[rows] = period_s(self.sensors[i])
        if self.sensors:
            s.sensor = self.sensors[-1]
        device_us = self.device_us[positions]
        segment = self.segment(keys)
        first = np.ones(n, dtype=bool)
        first[1:] = segment[1:] != segment[:-1]
        dt = np.where(first, first_dt, sample_dt_s(device_us, np.concatenate(([0], device_us[:-1]))))
        readings = _Readings(self, keys)
        time_s, t_host = self.time_s[positions], self.t_host[positions]
        temperature_c = raw["temperature"] * TEMPERATURE_SCALE
        # Every frame is in its table or among these now: the decoder's columns and the per-frame times go
        # before the estimators run (memory: an hour's frames are ~90 MB of them)
        del columns, raw, positions
        self.d.frames = {}
        self.time_s = self.device_us = self.t_host = self.chunk = None
        give_back_freed_memory()
        mag, gps = readings.for_estimators()
        run = self._estimate_run(keys, gyr, acc, dt, mag, gps, t_host)
        # The table's columns before the estimators' (``IMU``), each let go once written (``_imu_table``): the gyro
        # and the times are not held beside the table while the estimators run
        sensors = [time_s, device_us, (t_host - s.t0_host_ns) * 1e-9, *acc.T, *gyr.T, temperature_c]
        del mag, gps, gyr, device_us, t_host, temperature_c
        aiding_q = self._imu_table(keys, sensors, run, readings.any)
        readings.stage(acc, dt, aiding_q, time_s)

    def _imu_table(self, keys: np.ndarray, sensors: list, run: EstimateRun, aided: bool) -> np.ndarray:
        """The ``imu`` table made in one array: the samples' sensor columns and a gap row at each restart after
        the first sample, in the pipeline's order; the estimators' columns in another, in the product's form
        (``BatchSession.held_estimates``), written a stretch of samples at a time (``EstimateRun``). Streaming
        (``BatchSession.stream_estimates``), no estimator's columns are held: they are left to ``Streamed``.
        Returns the aiding estimator's quaternions if the session has readings it aids (``aided``: the compass
        heading and the position need its attitude at every sample; none else), which the readings' stage uses
        and lets go."""
        s, n = self.s, len(keys)
        bank = s.bank
        held = s.filters if not s.stream_estimates else ()
        aiding_q = np.empty((n, 4)) if aided and bank.aiding in s.filters else np.zeros((0, 4))
        diagnostics = bank.diagnostics()
        columns = IMU.column_names
        estimates = tuple(c for name in held for c in estimator_columns(name, diagnostics[name]))
        gaps = [(key, event) for key, (_, event) in zip(self.disc_keys.tolist(), self.discontinuities) if n and keys[0] < key]
        gap_at = np.searchsorted(keys, [key for key, _ in gaps], side="right")  # each gap row after the samples before it
        sample_rows = np.arange(n) + np.searchsorted(gap_at, np.arange(n), side="right")
        table = np.empty((n + len(gaps), len(columns)), order="F")  # each column written and read whole
        held_values = np.empty((len(table), len(estimates)), np.result_type(*map(held_dtype, estimates)) if estimates else float,
                               order="F")
        every_sample = _as_slice(sample_rows)
        for j in range(len(sensors)):
            table[every_sample, j], sensors[j] = sensors[j], None
        for row, (_, event) in zip(gap_at + np.arange(len(gaps)), gaps):
            table[row] = gap_row(event, len(columns))
            held_values[row] = np.nan
        index = {column: j for j, column in enumerate(columns)}
        held_index = {column.name: j for j, column in enumerate(estimates)}
        # From here the run reads its gyro and accelerometer from the table's columns: not kept twice
        run.gyr_rad_s, run.acc_g = (SampleColumns(table, sample_rows, [index[f"{quantity}_{a}_{unit}"] for a in "xyz"])
                                    for quantity, unit in (("gyr", "rad_s"), ("acc", "g")))
        for start, end, values in run.stretches(held if not len(aiding_q) or bank.aiding in held else (*held, bank.aiding)):
            rows = _as_slice(sample_rows[start:end])
            for name in held:
                for column, values_of in estimate_columns(name, *values[name]).items():
                    held_values[rows, held_index[column]] = values_of
            if len(aiding_q):
                aiding_q[start:end] = values[bank.aiding][0]
            self.progress(end, n)
        s.tables["imu"] = Table.holding(columns, table)
        held_values.flags.writeable = False
        s.held_estimates = {column.name: held_values[:, j] for j, column in enumerate(estimates)}
        if s.stream_estimates:
            s.streamed = Streamed(run, s.filters, sample_rows, tuple(
                c.name for name in s.filters for c in estimator_columns(name, diagnostics[name])))
        return aiding_q

    def _hold(self, columns, keys: np.ndarray) -> None:
        """IMU samples before the first usable CONFIG wait for it (``ConfigWait``, as the pipeline's do);
        sets the keys of held samples to where they are released (inf: never)."""
        first_config = self.sensor_keys[0] if self.sensor_keys else math.inf
        held = np.flatnonzero(keys < first_config)
        wait = ConfigWait(SensorConfig())
        counts = zip(*(columns.raw[f][held].tolist() for f in ACC_FIELDS))
        for k, time_s, acc_counts in zip(held.tolist(), self.time_s[columns.order[held]].tolist(), counts):
            released = wait.sample(k, time_s, acc_counts)
            if released is not None:  # the wait expired at sample k: the configuration it says from here
                release = float(keys[k])
                self.s.event(release, {"t_host_ns": int(columns.t_host_ns[k]), "kind": "warning", "message": wait.message})
                self.sensor_keys.insert(0, release)
                self.sensors.insert(0, wait.sensor)
                keys[released] = release
                return
        keys[wait.release()] = first_config

    def _sensor_at(self, keys: np.ndarray) -> np.ndarray:
        return np.searchsorted(np.array(self.sensor_keys), keys, side="right") - 1

    def mag_body(self, columns) -> np.ndarray:
        """Magnetometer readings in body axes (µT) with the mounting in effect at each frame."""
        keys = self.key(columns.order)
        body = np.empty((len(keys), 3))
        sensor_index = self._sensor_at(keys)
        counts = [columns.raw[f].astype(float) for f in MAG_FIELDS]
        for i in np.unique(sensor_index).tolist():
            rows = sensor_index == i
            _, _, mag_m = conversions(self.sensors[i] if i >= 0 else SensorConfig())
            body[rows] = np.column_stack(in_body_axes(mag_m, *(c[rows] for c in counts)))
        return body

    def _estimate_run(self, keys, gyr, acc, dt, mag, gps, t_host) -> EstimateRun:
        """The estimators' run over the samples (``EstimateRun``): the rest-bias calibrator first (its event),
        then the breaks between stretches, restarts and recorded settings changes, each change also applied
        to the session's estimators (their settings at the end, its event) where it happens."""
        s, bank = self.s, self.s.bank
        calibrator = bank.gyro_calibration
        measured_at = calibrator.measure(gyr, acc, dt, None, mag, gps)
        bias = None
        if measured_at is not None:
            bias = (measured_at, calibrator.bias_rad_s)
            s.event(keys[measured_at], {"t_host_ns": int(t_host[measured_at]), "kind": "gyro_bias", "bias_rad_s": list(bias[1])})
        settings = [(k, 0, i) for i, k in enumerate(self.change_keys) if self.changes[i][1]["kind"] == "settings"]
        breaks = []
        for key, kind, index in sorted(settings + [(k, 1, i) for i, k in enumerate(self.disc_keys.tolist())]):
            sample = int(np.searchsorted(keys, key))
            if kind == 1:
                breaks.append(Break(sample, None))
                continue
            event = self.changes[index][1]
            s._key = key
            apply_event(s, event)
            if event.get("name") in bank.estimators:
                breaks.append(Break(sample, event))
        setup = s.setup
        # The readings handed to the samples as the few rows that have one: held while an export streams
        return EstimateRun(bank.filters, setup.settings, setup.forced, bank.aiding, gyr, bias, acc, dt,
                           *(None if rows is None else SparseRows(rows) for rows in (mag, gps)), breaks)

    # -- gaps and link ----------------------------------------------------------------------------

    def _gaps(self) -> None:
        """A row of NaN (but time) in every table that has rows when the device clock restarts or jumps."""
        for key, (_, event) in zip(self.disc_keys.tolist(), self.discontinuities):
            for name, parts in self.rows.items():
                if any((k < key).any() for k, _ in parts):
                    width = len(self.s.tables[name].columns)
                    parts.append((np.array([key]), np.array([gap_row(event, width)])))

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


def _as_slice(rows: np.ndarray) -> np.ndarray | slice:
    """``rows`` (ascending, distinct) as a slice when they are consecutive: a copy through a slice is a
    block copy, through an index array one element at a time."""
    return slice(int(rows[0]), int(rows[-1]) + 1) if len(rows) and rows[-1] - rows[0] == len(rows) - 1 else rows


class _Readings:
    """The aiding stage of the pipeline (``session_parts.aiding.Aiding``, the same object and methods) driven
    over the session's columns in the pipeline's order: magnetometer, barometer and GPS readings, IMU
    samples and device restarts merged by their ``stage_key`` (``aiding.merged``).

    Twice, since the estimators run in between: first for what each sample hands the estimators
    (``for_estimators``), then, with the aiding estimator's attitudes, for the compass heading and the
    position (``stage``)."""

    def __init__(self, builder: _Builder, sample_keys: np.ndarray):
        self.b = builder
        frames = builder.d.frames
        self.mag, self.baro, self.gps = frames["MAG_RAW"], frames["BARO"], frames["GPS"]
        self.mag_time_s = builder.time_s[self.mag.order]
        self.mag_body = builder.mag_body(self.mag)
        self.pressure_pa = self.baro.scaled("pressure")
        self.gps_values = {f: self.gps.scaled(f) for f in self.gps.type.field_names}
        self.sample_keys = sample_keys
        self.n = len(sample_keys)
        self.stream = aiding.merged([(sample_keys, aiding.SAMPLE), (builder.disc_keys, aiding.RESTART),
                                     (builder.key(self.mag.order), aiding.MAG), (builder.key(self.baro.order), aiding.BARO),
                                     (builder.key(self.gps.order), aiding.GPS)])  # fmt: skip
        self.any = len(self.mag) + len(self.baro) + len(self.gps) > 0

    def for_estimators(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The magnetometer reading (body axes, µT) and GPS fix each sample hands the estimators (NaN rows
        for none; None when no sample has one)."""
        return aiding.handed_to_samples(self.stream, self.n, self.mag_body, self.gps_values)

    def stage(self, acc: np.ndarray, dt: np.ndarray, aiding_q: np.ndarray, time_s: np.ndarray) -> None:
        """The magnetometer table with the compass heading, and the position table, from the aiding
        estimator's attitude as the pipeline has it at each reading and sample."""
        b = self.b
        if not self.any:
            return
        driven = bool(b.s.filters)  # the aiding estimator's attitude drives heading and position
        heading, at, rows = aiding.heading_and_position(self.stream, self.mag_body, self.pressure_pa, self.gps_values,
                                                        aiding_q if driven else None, acc, dt)
        if len(self.mag):
            shown = [self.mag.scaled(f) for f in MAG_FIELDS]
            b.add("mag_raw", b.key(self.mag.order), np.column_stack([self.mag_time_s, *shown, heading]))
        if len(at):
            b.add("position", self.sample_keys[at], np.column_stack([time_s[at], rows]))

"""The computation of a session: timestamped chunks -> frames -> physical units -> estimators -> tables.

No threads and no I/O: the same ``Pipeline.feed`` serves the live reader thread, replay and the
tests, so one recording always gives the same numbers. Device timestamps drive ``dt``; every table's
``time_s`` is the session time of ``SessionClock`` (docs/time.md). When the device clock restarts or
jumps, the event is recorded, the estimators start over, and every table gets a gap row (NaN in all
columns but ``time_s``).

The pipeline is a dispatcher from frame type to a handler, one for every frame type of the spec.
Every downlink frame lands in a table (``catalogue``): most in a table of their own, in physical
units; ``IMU_RAW`` through the IMU stage (units, mounting, estimators) into ``imu``; ``ATTITUDE``
into ``onboard``; magnetometer, barometer and GPS readings also go to the aiding stage
(``aiding.py``) for the estimators and the position. ``CONFIG`` and ``ACK`` are events as well. An
uplink frame (a COMMAND echoed by a loopback, another sender) is counted in ``unexpected_frames``
and said once per type; no frame stops a session. Frames are read by field name.

Until the first ``CONFIG`` frame the full scales are unknown, so ``IMU_RAW`` frames wait
(``ConfigWait``, up to ``HOLD_FOR_CONFIG_US`` of session time); after that the assumed
``SensorConfig`` is used and a warning event is recorded. A later ``CONFIG`` takes effect from its
position in the stream, unless it changes the full scales or the mounting without a device restart
since the CONFIG in use (``ConfigGuard``): then a ``config_conflict`` event says what changed and the
scales in use stay until the user accepts (``resolve_config``; files: ``accept_config_changes``).

The rules here are the session's only copy: the batch path (``batch.py``) calls the same functions
(``conversions``, ``in_body_axes``, ``sample_dt_s``, ``ConfigWait``, ``ConfigGuard``, ``gap_row``, the aiding stage's
``Aiding``) on its columns and orders what it computed by ``stage_key``.

Two protocol front-ends turn bytes into the stages' input: the project's own frames (``GsFrontEnd``,
the dispatcher above) and an autopilot's MAVLink (``session_makers/mavlink_front.py``: records already in
body axes and physical units, placed on the same ``SessionClock``). ``protocol`` picks one; the
stages, the tables and the catalogue are the same.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
from operator import itemgetter

from firmware_protocol import SPEC, Frame, StreamDecoder
from firmware_protocol.spec import Spec
from groundstation import mounting
from groundstation.estimation import settings_as_json
from groundstation.session_parts.aiding import Aiding
from groundstation.session_parts.catalogue import session_catalogue
from groundstation.session_parts.clock import SessionClock
from groundstation.session_parts.estimators import EstimatorBank
from groundstation.session_parts.link import LinkStats
from groundstation.session_makers.mavlink_front import MavlinkFrontEnd
from groundstation.session_parts.table import LIVE_CHUNK_ROWS, Table
from groundstation.units import ACCEL_LSB_PER_G, GYRO_LSB_PER_DPS

DEFAULT_FILTERS = ("ahf",)
PROTOCOLS = ("gs", "mavlink")  # what a source speaks (``source.protocol``): the project's frames, an autopilot's MAVLink
HOLD_FOR_CONFIG_US = 1_000_000


def scales(frame_type, *names: str) -> tuple[float, ...]:
    """The spec's scales (counts -> physical units) of a frame type's fields, by name."""
    by_name = {f.name: f.scale for f in frame_type.fields}
    return tuple(by_name[name] for name in names)


def values_of(frame_type, *names: str) -> itemgetter:
    """Reads the named fields, in that order, from a frame's raw values (a tuple in the spec's order)."""
    return itemgetter(*(frame_type.field_names.index(name) for name in names))


_IMU, _ATTITUDE, _MAG = SPEC.frame("IMU_RAW"), SPEC.frame("ATTITUDE"), SPEC.frame("MAG_RAW")
ACC_FIELDS, GYR_FIELDS, MAG_FIELDS = ("acc_x", "acc_y", "acc_z"), ("gyr_x", "gyr_y", "gyr_z"), ("mag_x", "mag_y", "mag_z")
Q_FIELDS = ("q_w", "q_x", "q_y", "q_z")
Q_SCALES = scales(_ATTITUDE, *Q_FIELDS)  # Q2.14 -> 1
(LAMBDA_SCALE,) = scales(_ATTITUDE, "lambda_gain")
MAG_SCALES = scales(_MAG, *MAG_FIELDS)  # counts -> µT
(TEMPERATURE_SCALE,) = scales(_IMU, "temperature")  # counts -> °C
_BARO_SCALES = scales(SPEC.frame("BARO"), "pressure", "temperature")  # -> Pa, °C
# The fields each stage reads, by frame type, in the order it reads them.
_STAGE_FIELDS = {"IMU_RAW": (*ACC_FIELDS, *GYR_FIELDS, "temperature"), "ATTITUDE": (*Q_FIELDS, "lambda_gain", "flags"),
                 "MAG_RAW": MAG_FIELDS, "BARO": ("pressure", "temperature")}

# What happens at one frame, in this order: the recorded settings changes that apply before the chunk
# the frame came with (``replay.SettingsSchedule``), then the device clock's discontinuity at the frame
# (its event, the estimators' restart, the gap rows: ``Pipeline.place``), then the frame's handler.
# The pipeline does it by the order of its calls; the batch path sorts what it computed by ``stage_key``.
SETTINGS, DISCONTINUITY, HANDLER = range(3)


def stage_key(frame_position, stage: int):
    """The place of a stage at a frame (its position among the frames the decoder returned; numbers or
    arrays) in the pipeline's order."""
    return 3.0 * frame_position + stage


@dataclasses.dataclass(frozen=True)
class SensorConfig:
    """What CONFIG says about the IMU; the defaults are the MPU-6050's power-on full scales."""

    accel_fs_g: int = 2
    gyro_fs_dps: int = 250
    rate_hz: int = 100
    mounting: int = mounting.DEFAULT_MOUNTING


def folded(matrix, scales) -> list[tuple[float, float, float]]:
    """A mounting matrix with each sensor axis's scale folded in: sensor counts -> body units in one product."""
    return [tuple(float(x) * s for x, s in zip(row, scales)) for row in matrix]


def conversions(sensor: SensorConfig) -> tuple[list, list, list]:
    """The folded matrices (accelerometer -> g, gyro -> rad/s, magnetometer -> µT, body axes) of a sensor
    configuration; ValueError for a mounting index outside 0-23 or a rate that is not positive."""
    m = mounting.matrix(sensor.mounting)  # raises ValueError for an index outside 0-23
    if sensor.rate_hz <= 0:
        raise ValueError(f"output rate {sensor.rate_hz} Hz")
    return (folded(m, (1.0 / ACCEL_LSB_PER_G[sensor.accel_fs_g],) * 3),
            folded(m, (math.radians(1.0) / GYRO_LSB_PER_DPS[sensor.gyro_fs_dps],) * 3), folded(m, MAG_SCALES))


def in_body_axes(m, x, y, z) -> tuple:
    """Sensor counts ``x, y, z`` through a folded matrix: body axes, physical units. Numbers or arrays
    (the same operations in the same order: the live and the batch path agree bit for bit)."""
    (m0, m1, m2), (m3, m4, m5), (m6, m7, m8) = m
    return (m0 * x + m1 * y + m2 * z, m3 * x + m4 * y + m5 * z, m6 * x + m7 * y + m8 * z)


def period_s(sensor: SensorConfig) -> float:
    """``dt`` of a segment's first IMU sample (no previous device time): one output period."""
    return 1.0 / sensor.rate_hz


def sample_dt_s(t_us, last_us):
    """``dt`` between two IMU samples of one segment from their device times (µs); numbers or arrays."""
    return (t_us - last_us) * 1e-6


def hold_expired(time_s, first_held_s):
    """IMU samples held for a CONFIG since ``first_held_s`` are converted with the assumed scales now."""
    return time_s - first_held_s >= HOLD_FOR_CONFIG_US * 1e-6


def gap_row(event: dict, width: int) -> tuple:
    """The row a discontinuity puts in every table that has rows: NaN but ``time_s``, between the
    session times on either side."""
    return (0.5 * (event["session_time_before_s"] + event["session_time_s"]),) + (math.nan,) * (width - 1)


class ConfigWait:
    """Until the first usable CONFIG the full scales are unknown, so IMU samples wait, up to
    ``HOLD_FOR_CONFIG_US`` of session time; after that the configuration is assumed (``without_config``:
    the accelerometer's full scale inferred from the held samples where they allow it) and said.

    ``sample(item, time_s, acc_counts)`` holds one (any item: the caller's; its accelerometer counts x, y,
    z) and returns every held item, this one included, once the wait has expired (else None): then
    ``sensor`` and ``message`` (the warning) say what applies from there. ``release()`` hands them all
    over (a usable CONFIG). The pipeline calls it per sample; the batch path over the samples before
    the first CONFIG.
    """

    def __init__(self, assumed: SensorConfig) -> None:
        self.assumed = assumed
        self.sensor: SensorConfig | None = None  # once the wait expired
        self.message: str | None = None
        self._held: list = []
        self._norms: list[float] = []  # of the held samples' accelerometer counts
        self._first_s = math.nan

    def sample(self, item, time_s: float, acc_counts) -> list | None:
        if not self._held:
            self._first_s = time_s
        self._held.append(item)
        self._norms.append(math.hypot(*acc_counts))
        if not hold_expired(time_s, self._first_s):
            return None
        self.sensor, self.message = without_config(self.assumed, self._norms)
        return self.release()

    def release(self) -> list:
        held, self._held, self._norms = self._held, [], []
        return held


STILL_SPREAD = 0.05  # held samples whose accelerometer norms' median absolute deviation is under 5 % are at rest
SNAP_TOLERANCE = 0.15  # a median norm within 15 % of 1 g at a full scale is 1 g at that scale (the scales are 2x apart)


def without_config(assumed: SensorConfig, norms_counts: list[float]) -> tuple[SensorConfig, str]:
    """The configuration to convert with when no CONFIG came, and the warning that says so. At rest the
    accelerometer feels 1 g, so where the held samples are still (their norms' median absolute deviation
    under ``STILL_SPREAD``) their median norm, snapped to the full scale whose 1 g it is (within
    ``SNAP_TOLERANCE``), gives the accelerometer's full scale; the gyro's and the mounting are assumed."""
    median = statistics.median(norms_counts)
    spread = statistics.median(abs(n - median) for n in norms_counts)
    stretch = f"{len(norms_counts)} samples held for a CONFIG"
    sensor, accel = assumed, f"accelerometer full scale ±{assumed.accel_fs_g} g assumed (the {stretch} were not still)"
    if median > 0 and spread < STILL_SPREAD * median:
        fs_g = min(ACCEL_LSB_PER_G, key=lambda fs: abs(math.log(median / ACCEL_LSB_PER_G[fs])))
        at_rest_g = median / ACCEL_LSB_PER_G[fs_g]
        if abs(at_rest_g - 1.0) < SNAP_TOLERANCE:
            sensor = dataclasses.replace(assumed, accel_fs_g=fs_g)
            accel = (f"accelerometer full scale ±{fs_g} g inferred (the {stretch} were still, their median norm "
                     f"{at_rest_g:.3f} g at ±{fs_g} g)")
        else:
            accel = (f"accelerometer full scale ±{assumed.accel_fs_g} g assumed (the {stretch} were still, but "
                     f"their median norm, {at_rest_g:.3f} g at ±{fs_g} g, is 1 g at no full scale)")
    return sensor, (f"no CONFIG frame: {accel}; gyro full scale ±{sensor.gyro_fs_dps} °/s and mounting "
                    f"{sensor.mounting} assumed; rates and attitudes are wrong if the aircraft differs")


def unexpected_frame_event(t_host_ns: int, name: str) -> dict:
    """The event of the first frame of a type the aircraft never sends (an uplink COMMAND echoed by a
    loopback or a radio, another sender): such frames are counted and ignored, never a stopped session."""
    return {"t_host_ns": t_host_ns, "kind": "warning",
            "message": f"unexpected {name} frame on the downlink (a ground-to-aircraft frame: a loopback or "
                       "another sender?); it and any more are counted and ignored"}


def impossible_config_message(values: dict) -> str:
    return f"CONFIG with impossible values {values}; keeping the previous conversion"


def sensor_of(values: dict) -> SensorConfig:
    """The SensorConfig a CONFIG frame's values say; KeyError or ValueError when they cannot be one."""
    sensor = SensorConfig(values["accel_fs_g"], values["gyro_fs_dps"], values["rate_hz"], values["mounting"])
    conversions(sensor)
    return sensor


def config_changes(in_use: SensorConfig, new: SensorConfig) -> list[str]:
    """What ``new`` changes of the full scales and the mounting ``in_use``, in words (the rate may change freely)."""
    said = [("accelerometer full scale", "accel_fs_g", "±{} g"), ("gyro full scale", "gyro_fs_dps", "±{} °/s"),
            ("mounting", "mounting", "{}")]
    return [f"{what} {form.format(getattr(in_use, field))} → {form.format(getattr(new, field))}"
            for what, field, form in said if getattr(in_use, field) != getattr(new, field)]


class ConfigGuard:
    """A sensor's full scales and mounting change only with a device restart (no command changes them), so
    a CONFIG that changes them without one is not trusted by arrival (a forged or corrupted frame, another
    sender: one such CONFIG rescaled a whole session by 4x, silently). ``config(t_host_ns, sensor)`` says
    whether a usable CONFIG's sensor applies, and the ``config_conflict`` event when it changes them: it is
    held (the data keeps the scales in use) unless ``accept_changes``; ``resolve`` is the user's answer to
    a held one. The pipeline calls it per CONFIG, the batch path over its CONFIGs and restarts in order."""

    def __init__(self, accept_changes: bool = False):
        self.accept_changes = accept_changes
        self.trusted: SensorConfig | None = None  # from the last CONFIG applied; None before the first
        self.restarted = False  # a device_reset since that CONFIG
        self.held: SensorConfig | None = None  # a conflicting CONFIG's sensor awaiting the user's answer
        self._said: set[SensorConfig] = set()  # conflicts already reported since the last restart

    def device_reset(self) -> None:
        self.restarted = True

    def config(self, t_host_ns: int, sensor: SensorConfig) -> tuple[bool, dict | None]:
        """(whether ``sensor`` applies from here, the ``config_conflict`` event to record, if any)."""
        if self.trusted is None or self.restarted:
            self._trust(sensor)
            return True, None
        changes = config_changes(self.trusted, sensor)
        if not changes:  # the scales and mounting in use (the device answering a request): a held one stays held
            self.trusted = sensor
            return True, None
        if self.accept_changes:
            self._trust(sensor)
            return True, self._event(t_host_ns, changes, "accepted (--accept-config-changes)")
        self.held = sensor
        if sensor in self._said:
            return False, None
        self._said.add(sensor)
        return False, self._event(t_host_ns, changes, f"kept ±{self.trusted.accel_fs_g} g, ±{self.trusted.gyro_fs_dps} °/s "
                                  f"and mounting {self.trusted.mounting} until accepted")

    def resolve(self, t_host_ns: int, accept: bool) -> tuple[SensorConfig | None, dict | None]:
        """The user's answer to the held CONFIG: (the sensor to apply from here, or None; its event)."""
        held, self.held = self.held, None
        if held is None:
            return None, None
        if accept:
            self._trust(held)
        return (held if accept else None), {"t_host_ns": t_host_ns, "kind": "config_accepted" if accept else "config_kept",
                                            "accel_fs_g": held.accel_fs_g, "gyro_fs_dps": held.gyro_fs_dps,
                                            "mounting": held.mounting}

    def _trust(self, sensor: SensorConfig) -> None:
        self.trusted, self.restarted, self.held = sensor, False, None
        self._said.clear()

    @staticmethod
    def _event(t_host_ns: int, changes: list[str], outcome: str) -> dict:
        return {"t_host_ns": t_host_ns, "kind": "config_conflict", "changes": changes,
                "message": f"CONFIG changes {', '.join(changes)} without a device restart (a forged or damaged frame, "
                           f"another sender?): {outcome}"}


class Pipeline:
    """Feed ``(t_host_ns, bytes)`` chunks; read ``tables`` (``imu``, ``onboard`` and one per frame, as
    ``catalogue`` describes them), ``events``, ``link``, ``config``.

    ``filters`` names the host estimators; ``aiding`` the one whose attitude the compass heading and
    the position use (default ``estimation.aiding_estimator``); ``settings`` maps a name to
    setting overrides (the recorded settings); ``forced`` to overrides that win over everything,
    including settings changed later in the session (the what-if ``--set`` of replay and export).
    ``vehicle_system``: on a MAVLink link, the system id the user picked as the vehicle (else the first
    autopilot heard). ``keep_rows``: a live session's bound on every table's rows (``table.LIVE_KEEP_ROWS``;
    None: every row stays, as a replay or a file needs). ``compile_in_background``: a live session's, which
    starts before numba has compiled its estimators (``EstimatorBank``).
    """

    def __init__(self, filters=DEFAULT_FILTERS, settings=None, forced=None, assumed_sensor: SensorConfig | None = None,
                 spec: Spec = SPEC, protocol: str = "gs", aiding: str | None = None, vehicle_system: int | None = None,
                 accept_config_changes: bool = False, keep_rows: int | None = None, compile_in_background: bool = False):
        if protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {protocol!r} (known: {', '.join(PROTOCOLS)})")
        self.protocol = protocol
        self.bank = EstimatorBank(filters, settings, forced, aiding, compile_in_background)
        self.filters = self.bank.filters
        self.assumed_sensor = assumed_sensor or SensorConfig()
        self.clock = SessionClock()
        self.keep_rows = keep_rows
        self.link = LinkStats(self.new_table)
        self.front = GsFrontEnd(self, spec) if protocol == "gs" else MavlinkFrontEnd(self, vehicle_system=vehicle_system)
        self.decoder = self.front.decoder  # ``decoder.stats``: the link's counters (firmware_protocol.DecoderStats)
        self.catalogue = self.front.catalogue(session_catalogue(self.bank.diagnostics(), spec))
        self.tables = {info.name: self.new_table(info.column_names) for info in self.catalogue}
        self.imu, self.onboard = self.tables["imu"], self.tables["onboard"]
        self.aiding = Aiding()
        self.config: dict | None = None  # the values of the last CONFIG frame
        self.sensor: SensorConfig | None = None  # in use for conversion; None while holding
        self.parameters: dict[str, float] = {}  # an autopilot's, as last reported (MAVLink PARAM_VALUE)
        self.events: list[dict] = []  # what happened, in stream order: config, warnings, settings, acks
        self.unexpected_frames: dict[str, int] = {}  # frames of uplink types that came down, by type name
        self.t0_host_ns: int | None = None  # arrival of the first chunk: the origin of host times
        self.config_guard = ConfigGuard(accept_config_changes)  # ``config_guard.held``: a CONFIG awaiting the user
        self._config_wait = ConfigWait(self.assumed_sensor)  # IMU samples (t_host_ns, frame, time_s, device_us) until a CONFIG
        self._last_us: int | None = None
        self._time_s = math.nan  # session time of the newest timestamped frame
        self._device_us = 0  # its device time, unwrapped within the clock's segment
        self._mag_m = folded(mounting.matrix(self.assumed_sensor.mounting), MAG_SCALES)  # until CONFIG says
        if protocol == "gs":  # the frame handlers write to the spec's tables, which a MAVLink session lacks
            # Each frame type's value scales (timestamp excluded), looked up once: rows are value x scale.
            self._scales = {t.id: tuple(f.scale for f in t.fields[1 if t.has_timestamp else 0 :]) for t in spec.frames}
            self._handlers = {t.id: self._frame_handler(t) for t in spec.frames}  # every type the decoder returns
            self._imu_values, self._attitude_values, self._mag_values, self._baro_values = (
                values_of(spec.frame(name), *names) for name, names in _STAGE_FIELDS.items())
            self._acc_values = values_of(spec.frame("IMU_RAW"), *ACC_FIELDS)  # what ConfigWait infers from

    @property
    def estimators(self):
        return self.bank.estimators

    def new_table(self, columns) -> Table:
        """A table of this session: within ``keep_rows`` if it has that bound."""
        if self.keep_rows is None:
            return Table(columns)
        return Table(columns, chunk_rows=min(LIVE_CHUNK_ROWS, self.keep_rows), keep_rows=self.keep_rows)

    # -- input ----------------------------------------------------------------------------------

    def feed(self, t_host_ns: int, data: bytes) -> int:
        """Decode one chunk that arrived at ``t_host_ns``; returns the IMU samples it completed."""
        if self.t0_host_ns is None:
            self.t0_host_ns = t_host_ns
        before = len(self.imu)
        self.front.feed(t_host_ns, data)
        return len(self.imu) - before

    def take_uplink(self) -> bytes:
        """Bytes the front-end wants sent to the aircraft now (MAVLink stream-rate requests; else none)."""
        return self.front.take_uplink()

    def place(self, t_host_ns: int, t_us: int) -> None:
        """A device timestamp on the session clock: sets the session time of what follows."""
        clock = self.clock
        self._time_s = clock.place(t_host_ns, t_us)
        if clock.event is not None:
            self._discontinuity(clock.event)
        self._device_us = clock.device_us  # dt never spans a discontinuity

    def change_settings(self, name: str, overrides: dict[str, float], t_host_ns: int = 0) -> None:
        """Change an estimator's settings from this point of the stream, keeping its attitude."""
        self.bank.change(name, overrides)
        self.events.append({"t_host_ns": t_host_ns, "kind": "settings", "name": name, "settings": settings_as_json(overrides)})

    def settings(self) -> dict[str, dict[str, float]]:
        return self.bank.settings()

    def settings_json(self) -> dict[str, dict[str, float | str]]:
        return self.bank.settings_json()

    # -- frames ---------------------------------------------------------------------------------

    def _frame_handler(self, frame_type):
        """The handler of one frame type: a stage for the frames that feed one, a table row for any other
        downlink frame, and for an uplink type (the aircraft never sends one) a count."""
        if frame_type.direction != "down":
            return self._unexpected
        special = {"IMU_RAW": self._imu, "ATTITUDE": self._attitude, "CONFIG": self._config, "ACK": self._ack,
                   "MAG_RAW": self._magnetometer, "BARO": self._barometer, "GPS": self._gps}.get(frame_type.name)
        if special is not None:
            return special
        table = self.tables[frame_type.name.lower()]
        return lambda t_host_ns, frame: table.append(self._row(frame))

    def _row(self, frame: Frame) -> list[float]:
        """Session time, then the frame's values (timestamp excluded) in physical units."""
        raw = frame[2][1:] if frame[3] is not None else frame[2]
        return [self._time_s, *(r * s for r, s in zip(raw, self._scales[frame[0].id]))]

    def _config(self, t_host_ns: int, frame: Frame) -> None:
        self.config = frame.values
        self.tables["config"].append(self._row(frame))
        self.events.append({"t_host_ns": t_host_ns, "kind": "config", **self.config})
        if (warning := self.front.decoder.schema_warning) is not None:
            self._warn(t_host_ns, warning)
        try:
            sensor = sensor_of(self.config)
        except (KeyError, ValueError):
            self._warn(t_host_ns, impossible_config_message(self.config))
            return
        applies, event = self.config_guard.config(t_host_ns, sensor)
        if event is not None:
            self.events.append(event)
        if not applies:
            return
        self._use_sensor(sensor)
        for sample in self._config_wait.release():
            self._imu_sample(*sample)

    def resolve_config(self, accept: bool, t_host_ns: int = 0) -> None:
        """The user's answer to a held CONFIG (``config_guard.held``): its scales from here, or the ones in use."""
        sensor, event = self.config_guard.resolve(t_host_ns, accept)
        if event is not None:
            self.events.append(event)
        if sensor is not None:
            self._use_sensor(sensor)

    def _unexpected(self, t_host_ns: int, frame: Frame) -> None:
        name = frame[0].name
        seen = self.unexpected_frames.get(name, 0)
        self.unexpected_frames[name] = seen + 1
        if not seen:
            self.events.append(unexpected_frame_event(t_host_ns, name))

    def _ack(self, t_host_ns: int, frame: Frame) -> None:
        """The aircraft's answer to a COMMAND (``LiveSession.send_command``)."""
        self.tables["ack"].append(self._row(frame))
        self.events.append({"t_host_ns": t_host_ns, "kind": "ack", **frame.values})

    def _use_sensor(self, sensor: SensorConfig) -> None:
        # Scale and mounting folded into one matrix each: three dot products per vector per sample.
        self._acc_m, self._gyr_m, self._mag_m = conversions(sensor)
        self.sensor = sensor

    def _imu(self, t_host_ns: int, frame: Frame) -> None:
        if self.sensor is not None:
            self._imu_sample(t_host_ns, frame, self._time_s, self._device_us)
            return
        wait = self._config_wait
        released = wait.sample((t_host_ns, frame, self._time_s, self._device_us), self._time_s, self._acc_values(frame[2]))
        if released is not None:
            self._warn(t_host_ns, wait.message)
            self._use_sensor(wait.sensor)
            for sample in released:
                self._imu_sample(*sample)

    def _imu_sample(self, t_host_ns: int, frame: Frame, time_s: float, t_us: int) -> None:
        """One IMU sample at session time ``time_s``, device time ``t_us`` (unwrapped within its segment)."""
        cx, cy, cz, rx, ry, rz, temperature = self._imu_values(frame[2])
        acc = in_body_axes(self._acc_m, cx, cy, cz)
        gyr = in_body_axes(self._gyr_m, rx, ry, rz)
        self.imu_stage(t_host_ns, time_s, t_us, acc, gyr, temperature * TEMPERATURE_SCALE, period_s(self.sensor))

    def imu_stage(self, t_host_ns: int, time_s: float, t_us: int, acc: tuple, gyr: tuple, temperature_c: float,
                  first_dt_s: float) -> None:
        """One IMU sample in body axes (g, rad/s) through the estimators into ``imu``; ``dt`` from the
        device times, ``first_dt_s`` for the first sample of a segment."""
        dt_s = first_dt_s if self._last_us is None else sample_dt_s(t_us, self._last_us)
        self._last_us = t_us
        row = [time_s, t_us, (t_host_ns - self.t0_host_ns) * 1e-9, *acc, *gyr, temperature_c]
        mag, gps = self.aiding.take_for_estimators()
        row += self.bank.step(gyr, acc, dt_s, mag, gps)
        self.imu.append(row)
        bias = self.bank.new_gyro_bias()
        if bias is not None:
            self.events.append({"t_host_ns": t_host_ns, "kind": "gyro_bias", "bias_rad_s": list(bias)})
        if self.aiding.position_on and self.filters:
            self.tables["position"].append((time_s, *self.aiding.position_step(acc, self.bank.aiding_q(), dt_s)))
        self.link.on_sample(t_host_ns, t_us)

    def _magnetometer(self, t_host_ns: int, frame: Frame) -> None:
        mx, my, mz = self._mag_values(frame[2])
        body = in_body_axes(self._mag_m, mx, my, mz)
        sx, sy, sz = MAG_SCALES
        self.magnetometer_stage(body, (mx * sx, my * sy, mz * sz))

    def magnetometer_stage(self, body_ut: tuple, shown_ut: tuple) -> None:
        """Table row (``shown_ut``: the sensor's axes) with the compass heading from the aiding estimator's
        tilt; the body-axis field for the estimators."""
        heading = self.aiding.magnetometer(body_ut, self.bank.aiding_q())
        self.tables["mag_raw"].append((self._time_s, *shown_ut, heading))

    def _barometer(self, t_host_ns: int, frame: Frame) -> None:
        pressure, temperature = self._baro_values(frame[2])
        self.barometer_stage(pressure * _BARO_SCALES[0], temperature * _BARO_SCALES[1])

    def barometer_stage(self, pressure_pa: float, temperature_c: float) -> None:
        self.tables["baro"].append((self._time_s, pressure_pa, temperature_c))
        self.aiding.barometer(pressure_pa)

    def _gps(self, t_host_ns: int, frame: Frame) -> None:
        self.gps_stage(frame.scaled())

    def gps_stage(self, values: dict) -> None:
        """A GPS reading as the GPS frame's physical values (``lat``, ``lon``, ``alt``, ``vel_n`` ...)."""
        self.tables["gps"].append([self._time_s, *list(values.values())[1:]])
        self.aiding.gps(values)

    def _attitude(self, t_host_ns: int, frame: Frame) -> None:
        qw, qx, qy, qz, lam, flags = self._attitude_values(frame[2])
        sw, sx, sy, sz = Q_SCALES
        self.onboard_stage((qw * sw, qx * sx, qy * sy, qz * sz), lam * LAMBDA_SCALE, flags)

    def onboard_stage(self, q: tuple, lam: float, flags: float) -> None:
        """The aircraft's own attitude (w-first, body -> NED) at the current session time."""
        self.onboard.append((self._time_s, self._device_us, *q, lam, flags))

    def _discontinuity(self, event: dict) -> None:
        """The device clock restarted or jumped: record it, start the estimators over, break every table."""
        self.events.append(event)
        if event["kind"] == "device_reset":
            self.config_guard.device_reset()
        self.bank.restart()
        self.aiding.restart()
        self._last_us = None
        for table in self.tables.values():
            if len(table):
                table.append(gap_row(event, len(table.columns)))
        self.link.restart()

    def _warn(self, t_host_ns: int, message: str, about: str | None = None) -> None:
        """A warning event; ``about``: what it is about, when a product says it its own way (``imu_rate.IMU_RATE``)."""
        self.events.append({"t_host_ns": t_host_ns, "kind": "warning", "message": message} | ({"about": about} if about else {}))


class GsFrontEnd:
    """The project's own frames (``firmware_protocol``): each timestamped frame on the session clock,
    then the pipeline's handler for its type."""

    def __init__(self, pipeline: Pipeline, spec: Spec):
        self.pipeline = pipeline
        self.decoder = StreamDecoder(spec)

    @staticmethod
    def catalogue(catalogue):
        return catalogue

    def feed(self, t_host_ns: int, data: bytes) -> None:
        p = self.pipeline
        frames = self.decoder.feed(data, t_host_ns)
        p.link.on_chunk(t_host_ns, self.decoder.stats, len(frames))
        handlers = p._handlers
        for frame in frames:
            if frame[3] is not None:
                p.place(t_host_ns, frame[3])
            handlers[frame[0].id](t_host_ns, frame)

    @staticmethod
    def take_uplink() -> bytes:
        return b""  # the live session sends this protocol's commands itself


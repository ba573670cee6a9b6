"""The computation of a session: timestamped chunks -> frames -> physical units -> estimators -> tables.

No threads and no I/O: the same ``Pipeline.feed`` serves the live reader thread, replay and the
tests, so one recording always gives the same numbers. Device timestamps drive ``dt``; host arrival
times only feed the link statistics.

Until the first ``CONFIG`` frame the full scales are unknown, so ``IMU_RAW`` frames are held (up to
``HOLD_FOR_CONFIG_US`` of device time); after that the assumed ``SensorConfig`` is used and a
warning event is recorded. A later ``CONFIG`` takes effect from its position in the stream.
"""

from __future__ import annotations

import dataclasses
import math

from firmware_protocol import SPEC, Frame, StreamDecoder
from groundstation import geodesy, mounting
from groundstation.estimation import create
from groundstation.estimation.base import GpsFix
from groundstation.estimation.calibration import RestBiasCalibrator
from groundstation.estimation.compass import heading_rad
from groundstation.estimation.tilt import wrap_pi
from groundstation.position import DualChannel, linear_acc_ned_m_s2
from groundstation.session.link import LinkStats
from groundstation.session.table import Table
from groundstation.units import ACCEL_LSB_PER_G, GYRO_LSB_PER_DPS

DEFAULT_FILTERS = ("ahf",)
HOLD_FOR_CONFIG_US = 1_000_000
IMU_COLUMNS = (
    "time_s", "device_time_us", "host_time_s",
    "acc_x_g", "acc_y_g", "acc_z_g", "gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s", "temperature_c",
)  # fmt: skip
ONBOARD_COLUMNS = ("time_s", "device_time_us", "qw", "qx", "qy", "qz", "lambda", "flags")
_UNIT_SUFFIX = {"1": "", "enum": "", "bits": "", "index": "", "%": "_pct", "deg/s": "_deg_s", "m/s": "_m_s"}
_IMU_ID, _ATTITUDE_ID, _CONFIG_ID, _ACK_ID = (SPEC.frame(n).id for n in ("IMU_RAW", "ATTITUDE", "CONFIG", "ACK"))
_Q_SCALE = SPEC.frame("ATTITUDE").fields[1].scale
_LAMBDA_SCALE = SPEC.frame("ATTITUDE").fields[5].scale
_OTHER_TABLES = {SPEC.frame(n).id: n.lower() for n in ("STATUS", "MAG_RAW", "BARO", "GPS")}
_MAG_ID, _BARO_ID, _GPS_ID = (SPEC.frame(n).id for n in ("MAG_RAW", "BARO", "GPS"))
POSITION_COLUMNS = ("time_s", "pos_n_m", "pos_e_m", "pos_d_m", "vel_n_m_s", "vel_e_m_s", "vel_d_m_s")
_FIX_2D = SPEC.enums["gps_fix"].values["fix_2d"]
HEADING_COLUMN = "heading_deg"  # of the mag_raw table: tilt-compensated compass heading (estimation.compass)


@dataclasses.dataclass(frozen=True)
class SensorConfig:
    """What CONFIG says about the IMU; the defaults are the MPU-6050's power-on full scales."""

    accel_fs_g: int = 2
    gyro_fs_dps: int = 250
    rate_hz: int = 100
    mounting: int = mounting.DEFAULT_MOUNTING


def column_name(field) -> str:
    suffix = _UNIT_SUFFIX.get(field.unit, "_" + field.unit)
    return field.name + suffix


def estimator_columns(name: str, estimator) -> tuple[str, ...]:
    return (f"{name}_qw", f"{name}_qx", f"{name}_qy", f"{name}_qz") + tuple(f"{name}_{d}" for d in estimator.Diagnostics._fields)


class Pipeline:
    """Feed ``(t_host_ns, bytes)`` chunks; read ``imu``, ``onboard``, ``tables``, ``events``, ``link``.

    ``filters`` names the host estimators (``ahf`` first by convention); ``settings`` maps a name to
    setting overrides (the recorded settings); ``forced`` to overrides that win over everything,
    including settings changed later in the session (the what-if ``--set`` of replay and export).
    """

    def __init__(self, filters=DEFAULT_FILTERS, settings=None, forced=None, assumed_sensor: SensorConfig | None = None):
        self.filters = tuple(dict.fromkeys(filters))
        self._settings = {name: dict((settings or {}).get(name, {})) for name in self.filters}
        self._forced = {name: dict((forced or {}).get(name, {})) for name in self.filters}
        self.estimators = {name: create(name, self._effective(name)) for name in self.filters}
        self.assumed_sensor = assumed_sensor or SensorConfig()
        self.decoder = StreamDecoder()
        self.link = LinkStats()
        columns = IMU_COLUMNS + sum((estimator_columns(n, e) for n, e in self.estimators.items()), ())
        self.imu = Table(columns)
        self.onboard = Table(ONBOARD_COLUMNS)
        self.tables = {
            table: Table(("time_s",) + tuple(column_name(f) for f in SPEC.frame(table.upper()).fields))
            for table in _OTHER_TABLES.values()
        }
        self.tables["mag_raw"] = Table(self.tables["mag_raw"].columns + (HEADING_COLUMN,))
        # Aiding readings that arrived since the last IMU sample, handed to the estimators with the next one.
        self._mag_body_ut: tuple | None = None
        self._gps_fix: GpsFix | None = None
        # Position (seed 004) from the first estimator's attitude, once a barometer or GPS reading arrives:
        # NED metres from the first GPS fix, height from the first barometer reading.
        self.position = DualChannel()
        self.tables["position"] = Table(POSITION_COLUMNS)
        self._position_on = False
        self._baro_ground_pa: float | None = None
        self._gps_origin: tuple[float, float, float] | None = None
        self._baro_alt_m: float | None = None
        self._gps_pos_ned_m: tuple | None = None
        self._gps_vel_ned_m_s: tuple | None = None
        self.config: dict | None = None  # the values of the last CONFIG frame
        self.sensor: SensorConfig | None = None  # in use for conversion; None while holding
        self.events: list[dict] = []  # what happened, in stream order: config, warnings, settings, acks
        self.gyro_calibration = RestBiasCalibrator()  # restart() measures again (the user's command)
        self._gyro_bias_recorded = None
        self._held: list[tuple[int, Frame]] = []
        self._t0_us: int | None = None
        self._t0_host_ns: int | None = None
        self._last_us: int | None = None
        self._last_q = {name: None for name in self.filters}

    # -- input ----------------------------------------------------------------------------------

    def feed(self, t_host_ns: int, data: bytes) -> int:
        """Decode one chunk that arrived at ``t_host_ns``; returns the IMU samples it completed."""
        if self._t0_host_ns is None:
            self._t0_host_ns = t_host_ns
        frames = self.decoder.feed(data)
        self.link.on_chunk(t_host_ns, self.decoder.stats, len(frames))
        before = len(self.imu)
        for frame in frames:
            frame_type, _, raw, t_us = frame  # unpacking a Frame is C-speed; its properties are not
            type_id = frame_type.id
            if self._t0_us is None and t_us is not None:
                self._t0_us = t_us
            if type_id == _IMU_ID:
                self._imu(t_host_ns, frame)
            elif type_id == _ATTITUDE_ID:
                self._attitude(raw, t_us)
            elif type_id == _CONFIG_ID:
                self._config(t_host_ns, frame)
            elif type_id == _ACK_ID:  # the aircraft's answer to a COMMAND (``LiveSession.send_command``)
                self.events.append({"t_host_ns": t_host_ns, "kind": "ack", **frame.values})
            elif type_id == _MAG_ID:
                self._magnetometer(frame, t_us)
            elif type_id in _OTHER_TABLES:
                values = frame.scaled()
                self.tables[_OTHER_TABLES[type_id]].append([(t_us - self._t0_us) / 1e6, *values.values()])
                if type_id == _GPS_ID and values["fix_type"] >= _FIX_2D:
                    self._gps(values)
                elif type_id == _BARO_ID:
                    self._barometer(values["pressure"])
        return len(self.imu) - before

    def change_settings(self, name: str, overrides: dict[str, float], t_host_ns: int = 0) -> None:
        """Change an estimator's settings from this point of the stream, keeping its attitude."""
        if name not in self.estimators:
            raise ValueError(f"{name} is not among this session's estimators ({', '.join(self.filters)})")
        self._settings[name].update(overrides)
        estimator = create(name, self._effective(name))  # validates before anything changes
        if self._last_q[name] is not None:
            estimator.reset(q0=self._last_q[name])
        self.estimators[name] = estimator
        self.events.append({"t_host_ns": t_host_ns, "kind": "settings", "name": name, "settings": dict(overrides)})

    def settings(self) -> dict[str, dict[str, float]]:
        """Every estimator's full settings as in effect now."""
        return {name: dataclasses.asdict(est.settings) for name, est in self.estimators.items()}

    def settings_json(self) -> dict[str, dict[str, float | str]]:
        """``settings()`` for a JSON file: JSON has no infinity, so non-finite values become strings."""
        return {n: {k: v if math.isfinite(v) else str(v) for k, v in s.items()} for n, s in self.settings().items()}

    def _effective(self, name: str) -> dict[str, float]:
        return {**self._settings[name], **self._forced[name]}

    # -- frames ---------------------------------------------------------------------------------

    def _config(self, t_host_ns: int, frame: Frame) -> None:
        self.config = frame.values
        self.events.append({"t_host_ns": t_host_ns, "kind": "config", **self.config})
        if self.decoder.schema_matches is False:
            self._warn(t_host_ns, "the firmware was built from another protocol spec (schema fingerprint "
                       f"0x{frame['schema_fingerprint']:08X}); its frames may be mis-decoded")
        try:
            sensor = SensorConfig(frame["accel_fs_g"], frame["gyro_fs_dps"], frame["rate_hz"], frame["mounting"])
            self._use_sensor(sensor)
        except (KeyError, ValueError):
            self._warn(t_host_ns, f"CONFIG with impossible values {self.config}; keeping the previous conversion")
            return
        self._release_held()

    def _use_sensor(self, sensor: SensorConfig) -> None:
        m = mounting.matrix(sensor.mounting)  # raises ValueError for an index outside 0-23
        acc_scale = 1.0 / ACCEL_LSB_PER_G[sensor.accel_fs_g]
        gyr_scale = math.radians(1.0) / GYRO_LSB_PER_DPS[sensor.gyro_fs_dps]
        # Scale and mounting folded into one matrix each: three dot products per vector per sample.
        self._acc_m = [tuple(float(x) * acc_scale for x in row) for row in m]
        self._gyr_m = [tuple(float(x) * gyr_scale for x in row) for row in m]
        self.sensor = sensor

    def _release_held(self) -> None:
        held, self._held = self._held, []
        for t_host_ns, frame in held:
            self._imu_sample(t_host_ns, frame)

    def _imu(self, t_host_ns: int, frame: Frame) -> None:
        if self.sensor is not None:
            self._imu_sample(t_host_ns, frame)
            return
        self._held.append((t_host_ns, frame))
        if frame[3] - self._held[0][1][3] >= HOLD_FOR_CONFIG_US:
            s = self.assumed_sensor
            self._warn(t_host_ns, f"no CONFIG frame: converting with assumed full scales ±{s.accel_fs_g} g, "
                       f"±{s.gyro_fs_dps} °/s, mounting {s.mounting}")
            self._use_sensor(s)
            self._release_held()

    def _imu_sample(self, t_host_ns: int, frame: Frame) -> None:
        _, _, (_, cx, cy, cz, rx, ry, rz, temperature), t_us = frame  # t_us: the unwrapped device time
        (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = self._acc_m
        (g0, g1, g2), (g3, g4, g5), (g6, g7, g8) = self._gyr_m
        acc = (a0 * cx + a1 * cy + a2 * cz, a3 * cx + a4 * cy + a5 * cz, a6 * cx + a7 * cy + a8 * cz)
        gyr = (g0 * rx + g1 * ry + g2 * rz, g3 * rx + g4 * ry + g5 * rz, g6 * rx + g7 * ry + g8 * rz)
        dt_s = 1.0 / self.sensor.rate_hz if self._last_us is None else (t_us - self._last_us) * 1e-6
        self._last_us = t_us
        row = [(t_us - self._t0_us) * 1e-6, t_us, (t_host_ns - self._t0_host_ns) * 1e-9, *acc, *gyr, temperature * 0.01]
        mag, gps, self._mag_body_ut, self._gps_fix = self._mag_body_ut, self._gps_fix, None, None
        # Gyro bias measured at rest, for the estimators that do not estimate their own (issue 13).
        bias = self.gyro_calibration.step(gyr, acc, dt_s)
        if bias is not None and bias != self._gyro_bias_recorded:
            self._gyro_bias_recorded = bias
            self.events.append({"t_host_ns": t_host_ns, "kind": "gyro_bias", "bias_rad_s": list(bias)})
        unbiased = gyr if bias is None else (gyr[0] - bias[0], gyr[1] - bias[1], gyr[2] - bias[2])
        for name, estimator in self.estimators.items():
            q, diag = estimator.step(gyr if getattr(estimator, "estimates_gyro_bias", False) else unbiased, acc, dt_s, mag, gps)
            self._last_q[name] = q
            row += q
            row += diag
        self.imu.append(row)
        if self._position_on and self.filters:
            self._position(row[0], acc, self._last_q[self.filters[0]], dt_s)
        self.link.on_sample(t_host_ns, t_us)

    def _position(self, time_s: float, acc_g: tuple, q: tuple, dt_s: float) -> None:
        acc_ned = linear_acc_ned_m_s2(acc_g, q)
        pos, vel = self.position.step(acc_ned, dt_s, self._baro_alt_m, self._gps_pos_ned_m, self._gps_vel_ned_m_s)
        self._baro_alt_m = self._gps_pos_ned_m = self._gps_vel_ned_m_s = None
        self.tables["position"].append((time_s, *pos, *vel))

    def _barometer(self, pressure_pa: float) -> None:
        if self._baro_ground_pa is None:
            self._baro_ground_pa = pressure_pa
        self._baro_alt_m = float(geodesy.pressure_altitude_m(pressure_pa, self._baro_ground_pa))
        self._position_on = True

    def _gps(self, values: dict) -> None:
        self._gps_fix = gps_fix(values)
        if self._gps_origin is None:
            self._gps_origin = (values["lat"], values["lon"], values["alt"])
        self._gps_pos_ned_m = tuple(geodesy.ned_from_geodetic(values["lat"], values["lon"], values["alt"], self._gps_origin).tolist())
        self._gps_vel_ned_m_s = (values["vel_n"], values["vel_e"], values["vel_d"])
        self._position_on = True

    def _magnetometer(self, frame: Frame, t_us: int) -> None:
        """Table row with the compass heading from the first estimator's tilt; the body-axis field for the estimators."""
        values = frame.scaled()
        sensor = self.sensor or self.assumed_sensor
        field_sensor = (values["mag_x"], values["mag_y"], values["mag_z"])
        self._mag_body_ut = tuple(sum(r * v for r, v in zip(row, field_sensor)) for row in mounting.matrix(sensor.mounting).tolist())
        q = self._last_q[self.filters[0]] if self.filters else None
        heading = math.degrees(float(heading_rad(q, self._mag_body_ut))) if q is not None else math.nan
        self.tables["mag_raw"].append([(t_us - self._t0_us) / 1e6, *values.values(), heading])

    def _attitude(self, raw: tuple, t_us: int) -> None:
        _, qw, qx, qy, qz, lam, flags = raw
        s = _Q_SCALE
        self.onboard.append(((t_us - self._t0_us) * 1e-6, t_us, qw * s, qx * s, qy * s, qz * s, lam * _LAMBDA_SCALE, flags))

    def _warn(self, t_host_ns: int, message: str) -> None:
        self.events.append({"t_host_ns": t_host_ns, "kind": "warning", "message": message})


def gps_fix(values: dict) -> GpsFix:
    """A GPS frame's values as the estimators take them; a heading outside 0..360° (0xFFFF) means none."""
    heading_deg = values["heading"]
    heading = math.radians(heading_deg) if 0.0 <= heading_deg <= 360.0 else math.nan
    return GpsFix(values["vel_n"], values["vel_e"], values["vel_d"], wrap_pi(heading))

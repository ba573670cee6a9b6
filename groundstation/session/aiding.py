"""The aiding sensors of a session: magnetometer, barometer and GPS readings for the estimators, and
the fused position (seed 004) they make possible.

Each reading is handed to the estimators with the next IMU sample (``take_for_estimators``). Once a
barometer or GPS reading arrives, every IMU sample also steps the dual-channel position filter on
the aiding estimator's attitude (``EstimatorBank.aiding``): NED metres from the first GPS fix, height
from the first barometer reading (docs/conventions.md).

The pipeline calls it per frame; the batch path (``batch._Readings``) and a flight log
(``autopilot/session.py``) drive the same object over their columns merged in the pipeline's order
(``merged``, ``handed_to_samples``, ``heading_and_position``), so the hand-over, the heading and the
position are one code.
"""

from __future__ import annotations

import math

import numpy as np

from firmware_protocol import SPEC
from groundstation import geodesy
from groundstation.estimation.base import GpsFix
from groundstation.estimation.compass import reading_heading_rad
from groundstation.estimation.tilt import wrap_pi
from groundstation.position import DualChannel, linear_acc_ned_m_s2

_FIX_2D = SPEC.enums["gps_fix"].values["fix_2d"]


class Aiding:
    def __init__(self) -> None:
        self.position = DualChannel()
        self.position_on = False  # from the first barometer or GPS reading
        self._baro_ground_pa: float | None = None
        self._gps_origin: tuple[float, float, float] | None = None
        self.restart()

    def restart(self) -> None:
        """Forget the readings waiting for the next IMU sample and the position's state (a device reset).

        The GPS origin and the barometer's ground pressure stay: positions after a reset stay comparable."""
        self.position.reset()
        self._mag_body_ut: tuple | None = None
        self._gps_fix: GpsFix | None = None
        self._baro_alt_m: float | None = None
        self._gps_pos_ned_m: tuple | None = None
        self._gps_vel_ned_m_s: tuple | None = None

    def take_for_estimators(self) -> tuple[tuple | None, GpsFix | None]:
        """The magnetometer reading (body axes, µT) and GPS fix that arrived since the last IMU sample."""
        taken = self._mag_body_ut, self._gps_fix
        self._mag_body_ut = self._gps_fix = None
        return taken

    def magnetometer(self, field_body_ut: tuple, q) -> float:
        """Keeps the reading for the estimators; returns the compass heading in degrees (NaN without attitude)."""
        self._mag_body_ut = field_body_ut
        return math.degrees(reading_heading_rad(q, field_body_ut)) if q is not None else math.nan

    def barometer(self, pressure_pa: float) -> None:
        if self._baro_ground_pa is None:
            self._baro_ground_pa = pressure_pa
        self._baro_alt_m = float(geodesy.pressure_altitude_m(pressure_pa, self._baro_ground_pa))
        self.position_on = True

    def gps(self, values: dict) -> None:
        """A GPS frame's physical values; ignored without at least a 2D fix."""
        if values["fix_type"] < _FIX_2D:
            return
        self._gps_fix = gps_fix(values)
        if self._gps_origin is None:
            self._gps_origin = (values["lat"], values["lon"], values["alt"])
        self._gps_pos_ned_m = tuple(geodesy.ned_from_geodetic(values["lat"], values["lon"], values["alt"], self._gps_origin).tolist())
        self._gps_vel_ned_m_s = (values["vel_n"], values["vel_e"], values["vel_d"])
        self.position_on = True

    def position_step(self, acc_g: tuple, q, dt_s: float) -> tuple:
        """One IMU sample through the position filter: (pos_n, pos_e, pos_d, vel_n, vel_e, vel_d)."""
        acc_ned = linear_acc_ned_m_s2(acc_g, q)
        pos, vel = self.position.step(acc_ned, dt_s, self._baro_alt_m, self._gps_pos_ned_m, self._gps_vel_ned_m_s)
        self._baro_alt_m = self._gps_pos_ned_m = self._gps_vel_ned_m_s = None
        return (*pos, *vel)


def gps_fix(values: dict) -> GpsFix:
    """A GPS frame's values as the estimators take them; a heading outside 0..360° (0xFFFF) means none."""
    heading_deg = values["heading"]
    heading = math.radians(heading_deg) if 0.0 <= heading_deg <= 360.0 else math.nan
    return GpsFix(values["vel_n"], values["vel_e"], values["vel_d"], wrap_pi(heading))


# What a merged stream of a session's aiding events holds, in the pipeline's order (``merged``).
RESTART, MAG, BARO, GPS, SAMPLE = range(5)


def merged(parts) -> Merged:
    """``(kind, index)`` of every event of ``parts`` (``(keys, kind)`` each, keys sorted within a part) in
    the order of their keys; events sharing a key keep the order of ``parts``, then their own."""
    parts = list(parts)
    keys = np.concatenate([np.asarray(k, dtype=float) for k, _ in parts])
    kinds = np.concatenate([np.full(len(k), kind, dtype=np.int8) for k, kind in parts])
    index = np.concatenate([np.arange(len(k)) for k, _ in parts])
    order = np.argsort(keys, kind="stable")
    return Merged(kinds[order], index[order])


class Merged:
    """A merged stream as two arrays, iterated as ``(kind, index)`` Python ints a block at a time: an hour
    at 100 Hz is 360,000 samples, 35 MB as a list of tuples and 3 MB as arrays."""

    BLOCK = 65_536

    def __init__(self, kinds: np.ndarray, index: np.ndarray):
        self.kinds, self.index = kinds, index

    def __len__(self) -> int:
        return len(self.kinds)

    def __iter__(self):
        for start in range(0, len(self.kinds), self.BLOCK):
            yield from zip(self.kinds[start:start + self.BLOCK].tolist(), self.index[start:start + self.BLOCK].tolist())


def handed_to_samples(stream, samples: int, mag_body: list, gps_values: list) -> tuple[np.ndarray | None, np.ndarray | None]:
    """What each of ``samples`` IMU samples hands the estimators (``take_for_estimators``) over a merged
    ``stream``: the magnetometer reading (body axes, µT) and GPS fix, NaN rows for none; None when no
    sample has one."""
    if not len(mag_body) and not len(gps_values):
        return None, None
    aiding = Aiding()
    mag, gps = np.full((samples, 3), math.nan), np.full((samples, 4), math.nan)
    with_mag, with_gps = False, False
    for kind, i in stream:
        if kind == SAMPLE:
            body, fix = aiding.take_for_estimators()
            if body is not None:
                mag[i], with_mag = body, True
            if fix is not None:
                gps[i], with_gps = fix, True
        elif kind == MAG:
            aiding.magnetometer(mag_body[i], None)
        elif kind == GPS:
            aiding.gps(gps_values[i])
        elif kind == RESTART:
            aiding.restart()
    return (mag if with_mag else None), (gps if with_gps else None)


def heading_and_position(stream, mag_body: list, pressure_pa: list, gps_values: list, aiding_q, acc_g, dt_s):
    """The compass heading of every magnetometer reading and the position rows, over a merged ``stream``,
    with the aiding estimator's attitude ``aiding_q`` at each sample (None: no estimator ran, so no
    heading and no position). Returns (headings in degrees, the samples with a position row, the rows)."""
    aiding = Aiding()
    qs, accs, dts = (None if aiding_q is None else _Rows(aiding_q)), _Rows(acc_g), _Rows(dt_s)
    heading = [math.nan] * len(mag_body)
    at, rows = [], []
    last = None  # the newest sample: its attitude is the one the compass and the position use
    for kind, i in stream:
        if kind == SAMPLE:
            if qs is not None:
                last = i
                if aiding.position_on:
                    at.append(i)
                    rows.append(aiding.position_step(accs[i], qs[i], dts[i]))
        elif kind == MAG:
            heading[i] = aiding.magnetometer(mag_body[i], None if last is None else qs[last])
        elif kind == BARO:
            aiding.barometer(pressure_pa[i])
        elif kind == GPS:
            aiding.gps(gps_values[i])
        elif kind == RESTART:
            aiding.restart()  # the attitude stays: EstimatorBank.restart keeps each estimator's last one
    return heading, at, rows


class _Rows:
    """An array's rows (or values) as Python floats, converted a block at a time as they are read in order:
    the whole array as lists would be ~150 bytes a row."""

    BLOCK = 65_536

    def __init__(self, values):
        self._values = np.asarray(values)
        self._first, self._rows = 0, []

    def __getitem__(self, i: int):
        if not self._first <= i < self._first + len(self._rows):
            self._first = i - i % self.BLOCK
            self._rows = self._values[self._first:self._first + self.BLOCK].tolist()
        return self._rows[i - self._first]

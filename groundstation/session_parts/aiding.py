"""The aiding sensors of a session: magnetometer, barometer and GPS readings for the estimators, and
the fused position (seed 004) they make possible.

Each reading is handed to the estimators with the next IMU sample (``take_for_estimators``). Once a
barometer or GPS reading arrives, every IMU sample also steps the dual-channel position filter on
the aiding estimator's attitude (``EstimatorBank.aiding``): NED metres from the first GPS fix, height
from the first barometer reading (docs/conventions.md).

The pipeline calls it per frame; the batch path (``batch._Readings``) and a flight log
(``session_makers/flight_log_session.py``) run its rules on whole columns merged in the pipeline's order (``merged``,
``handed_to_samples``, ``heading_and_position``), with no Python call per sample: the same heading
(``reading_heading_rad``'s rotation compiled), barometer altitude, GPS fix and position filter
(``DualChannel.run``: ``step``'s ``advance`` compiled), the same numbers bit for bit
(tests/session/test_one_rule_each.py, tests/autopilot/test_ulog_open_work.py).
"""

from __future__ import annotations

import math

import numpy as np

from firmware_protocol import SPEC
from groundstation import geodesy
from groundstation.estimation.base import GpsFix
from groundstation.estimation.compass import reading_heading_rad, reading_headings_deg
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


def merged(parts) -> tuple[np.ndarray, np.ndarray]:
    """``(kinds, indexes)``: the kind and index of every event of ``parts`` (``(keys, kind)`` each, keys
    sorted within a part) in the order of their keys; events sharing a key keep the order of ``parts``,
    then their own."""
    parts = list(parts)
    keys = np.concatenate([np.asarray(k, dtype=float) for k, _ in parts])
    kinds = np.concatenate([np.full(len(k), kind) for k, kind in parts])
    index = np.concatenate([np.arange(len(k)) for k, _ in parts])
    order = np.argsort(keys, kind="stable")
    return kinds[order], index[order]


def _handed(stream, kind: int, valid: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Which reading of ``kind`` (those ``valid`` among them) each sample takes, as ``Aiding`` hands them:
    a reading waits for the next sample, a later one before it replaces it, a restart drops it.
    Returns (the samples' places in the stream, the readings' indexes), one pair per sample that takes one."""
    kinds, index = stream
    at = np.flatnonzero(kinds == kind)
    if valid is not None:
        at = at[valid[index[at]]]
    samples_at = np.flatnonzero(kinds == SAMPLE)
    taker = np.searchsorted(samples_at, at)  # the next sample's rank among the samples
    restarts_at = np.flatnonzero(kinds == RESTART)
    kept = taker < len(samples_at)  # and no restart between the reading and its sample
    kept[kept] = np.searchsorted(restarts_at, samples_at[taker[kept]]) == np.searchsorted(restarts_at, at[kept])
    at, taker = at[kept], taker[kept]
    last = np.append(taker[1:] != taker[:-1], True)[: len(taker)]  # the latest reading before each sample
    return samples_at[taker[last]], index[at[last]]


def _fixes(gps: dict[str, np.ndarray], taken: np.ndarray) -> np.ndarray:
    """``gps_fix`` of the GPS readings ``taken``, as (n, 4) rows (a few a second: one by one, as live)."""
    rows = zip(*(np.asarray(values)[taken].tolist() for values in gps.values()))
    return np.array([gps_fix(dict(zip(gps, row))) for row in rows]).reshape(-1, 4)


def _fixed(gps: dict[str, np.ndarray]) -> np.ndarray:
    """The GPS readings ``Aiding.gps`` takes: all but those below a 2D fix."""
    return ~(np.asarray(gps["fix_type"]) < _FIX_2D)


def handed_to_samples(stream, samples: int, mag_body: np.ndarray, gps: dict[str, np.ndarray]) -> tuple[np.ndarray | None, np.ndarray | None]:
    """What each of ``samples`` IMU samples hands the estimators (``Aiding.take_for_estimators``) over a
    merged ``stream``: the magnetometer reading (body axes, µT; ``mag_body`` (n, 3)) and GPS fix (``gps``:
    the readings' columns, as ``Aiding.gps`` takes them), NaN rows for none; None when no sample has one."""
    if not len(mag_body) and not len(gps["fix_type"]):
        return None, None
    index = stream[1]
    mag, fix = np.full((samples, 3), math.nan), np.full((samples, 4), math.nan)
    taking, taken = _handed(stream, MAG)
    mag[index[taking]] = np.asarray(mag_body, dtype=float).reshape(-1, 3)[taken]
    with_mag = len(taking) > 0
    taking, taken = _handed(stream, GPS, _fixed(gps))
    fix[index[taking]] = _fixes(gps, taken)
    return (mag if with_mag else None), (fix if len(taking) else None)


def heading_and_position(stream, mag_body: np.ndarray, pressure_pa: np.ndarray, gps: dict[str, np.ndarray], aiding_q, acc_g, dt_s):
    """The compass heading of every magnetometer reading and the position rows, over a merged ``stream``,
    with the aiding estimator's attitude ``aiding_q`` at each sample (None: no estimator ran, so no
    heading and no position), as ``Aiding`` computes them reading by reading and sample by sample: the
    heading on the attitude of the last sample before the reading; from the first barometer reading or
    GPS fix on, every sample steps the position filter (``DualChannel.run``: its ``step`` compiled) with
    the readings handed to it. Returns (headings in degrees, the samples with a position row, the rows (n, 6))."""
    kinds, index = stream
    mag_body = np.asarray(mag_body, dtype=float).reshape(-1, 3)
    heading = np.full(len(mag_body), math.nan)
    nothing = np.zeros(0, dtype=int), np.zeros((0, 6))
    if aiding_q is None:
        return heading, *nothing
    q = np.asarray(aiding_q, dtype=float)
    samples_at, mags_at = np.flatnonzero(kinds == SAMPLE), np.flatnonzero(kinds == MAG)
    before = np.searchsorted(samples_at, mags_at) - 1  # the last sample before each reading (-1: none yet)
    seen = np.flatnonzero(before >= 0)
    for piece in _pieces(len(seen)):  # (the attitudes gathered a piece at a time: not a session's copy of them)
        readings = mags_at[seen[piece]]
        heading[index[readings]] = reading_headings_deg(q[index[samples_at[before[seen[piece]]]]], mag_body[index[readings]])
    del mags_at, before, seen
    fixed = _fixed(gps)
    gps_events = kinds == GPS
    fixes = np.zeros(len(kinds), dtype=bool)
    fixes[gps_events] = fixed[index[gps_events]]
    del gps_events
    aids_at = np.flatnonzero((kinds == BARO) | fixes)
    if not len(aids_at):
        return heading, *nothing
    stepping = samples_at[samples_at > aids_at[0]]  # the position is on from the first aiding reading
    del samples_at
    at, n = index[stepping], len(stepping)
    # The readings each stepping sample is handed (few: a rate of the IMU's), by the sample's row
    baro_rows, baro_alt = np.zeros(0, dtype=int), np.zeros(0)
    if len(pressure_pa):
        pressure_pa = np.asarray(pressure_pa, dtype=float)
        taking, taken = _handed(stream, BARO)
        ground_pa = pressure_pa[index[np.flatnonzero(kinds == BARO)[0]]]  # kept across restarts
        baro_rows, baro_alt = np.searchsorted(stepping, taking), geodesy.pressure_altitude_m(pressure_pa[taken], ground_pa)
    gps_rows, gps_pos, gps_vel = np.zeros(0, dtype=int), np.zeros((0, 3)), np.zeros((0, 3))
    if fixes.any():
        taking, taken = _handed(stream, GPS, fixed)
        first = index[np.flatnonzero(fixes)[0]]
        origin = (gps["lat"][first], gps["lon"][first], gps["alt"][first])  # kept across restarts
        gps_rows = np.searchsorted(stepping, taking)
        gps_pos = geodesy.ned_from_geodetic(gps["lat"][taken], gps["lon"][taken], gps["alt"][taken], origin)
        gps_vel = np.column_stack([gps["vel_n"][taken], gps["vel_e"][taken], gps["vel_d"][taken]])
    # The filter's state carries from piece to piece (``DualChannel.run`` continues): a restart forgets it
    # (``Aiding.restart``) before the first sample after it; between restarts, pieces of samples, so that its
    # inputs are a piece's, not a session's
    resets = np.unique(np.searchsorted(stepping, np.flatnonzero(kinds == RESTART)))
    resets = set(resets[resets < n].tolist())
    del stepping, fixes
    starts = np.union1d(list(resets), np.arange(0, n, _PIECE)).astype(int)
    acc_g, dt_s = np.asarray(acc_g, dtype=float), np.asarray(dt_s, dtype=float)
    position, rows = DualChannel(), np.empty((n, 6))
    for start, end in zip(starts.tolist(), [*starts[1:].tolist(), n]):
        if start in resets:
            position.reset()
        piece = at[start:end]
        baro, pos, vel = np.full(end - start, math.nan), np.full((end - start, 3), math.nan), np.full((end - start, 3), math.nan)
        b = slice(*np.searchsorted(baro_rows, [start, end]))
        baro[baro_rows[b] - start] = baro_alt[b]
        g = slice(*np.searchsorted(gps_rows, [start, end]))
        pos[gps_rows[g] - start], vel[gps_rows[g] - start] = gps_pos[g], gps_vel[g]
        rows[start:end, :3], rows[start:end, 3:] = position.run(linear_acc_ned_m_s2(acc_g[piece], q[piece]), dt_s[piece], baro, pos, vel)
    return heading, at, rows


_PIECE = 1 << 16  # samples a piece: 0.5 MB a column, a session of any length in memory of that size


def _pieces(n: int):
    """Consecutive slices of at most ``_PIECE`` over ``range(n)``."""
    return (slice(start, min(start + _PIECE, n)) for start in range(0, n, _PIECE))

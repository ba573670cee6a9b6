"""VQF: the versatile quaternion-based filter of Laidig & Seel (2023), through the ``vqf`` package.

The state of the art on the BROAD benchmark: strapdown gyro integration, the accelerometer low-passed
(τ_acc) in an almost inertial frame, gyro bias estimated at rest and in motion, rest detection, and a
magnetometer correction with disturbance rejection. This module only adapts it to the project's
interface and conventions; the filter is the package's compiled code.

Units and frames. ``vqf`` takes rad/s and m/s² (``acc_g`` × standard gravity here) and returns
quaternions that rotate sensor vectors into its earth frame, ENU (x east, y north, z up). It does not
care how the sensor is held, so the body FRD axes go in as they are. Out:

- with a magnetometer (once the first reading has arrived): ``q = q_ENU→NED ⊗ q_9D``,
  ``q_ENU→NED = (0, 1/√2, 1/√2, 0)`` (half turn about the north-east bisector: x ↔ y, z → -z), so yaw
  is magnetic heading;
- without: ``q = q_x(π) ⊗ q_6D``; the 6D heading is arbitrary, and this choice starts yaw at 0 on a
  level sensor as every other IMU-only estimator here does.

Diagnostics are VQF's own: rest detected, the gyro bias estimate (rad/s, body axes) and its standard
deviation, magnetic disturbance detected.

Sample period. VQF's coefficients are made for one period, the first integrated sample's interval;
``step`` gives every later sample to it whatever its interval (``dt_s`` decides only the guard's
holding, re-initialising and skipping, base.py). So jitter in the sample times (0.2 % on the
recordings) is not integrated: its cost on BROAD is in bench/bench_estimator_costs.out.md.

``run`` gives what stepping gives, bit for bit: the guard (``base.screen_rows``, compiled) judges every
row first; each stretch of rows that step would hand to VQF whole (gyro and accelerometer updated) goes
to ``updateBatch`` (the loop in compiled code), with (0, 0, 0) on the rows without a magnetometer
reading (VQF skips a zero reading, as step skips a missing one), and the rows between (held,
re-initialised, accelerometer skipped, waiting) take step's own code.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
import vqf as vqf_package

from groundstation import quaternion
from groundstation.estimation.base import (
    ACC_SKIPPED, INITIALISED, NO_UPDATE, SCREEN_ROWS_SIGNATURE, CommonSettings, Estimator, _compiled, _loaded, _rows, batch_inputs, screen_rows,
)
from groundstation.estimation.tilt import quaternion_product
from groundstation.units import STANDARD_GRAVITY_M_S2

_H = math.sqrt(0.5)
_ENU_TO_NED = (0.0, _H, _H, 0.0)
_UP_TO_DOWN = (0.0, 1.0, 0.0, 0.0)  # half turn about x: the 6D frame's z up becomes down


@dataclasses.dataclass(frozen=True)
class VqfSettings(CommonSettings):
    tau_acc_s: float = 3.0  # time constant of the accelerometer low-pass (VQF's default)
    tau_mag_s: float = 9.0  # time constant of the magnetometer heading correction
    rest_bias_est: bool = True  # gyro bias from rest phases
    motion_bias_est: bool = True  # gyro bias in motion (horizontal axes)
    mag_dist_rejection: bool = True


class VqfDiagnostics(NamedTuple):
    status: int
    rest: float  # 1.0 when VQF detects rest
    bias_x_rad_s: float  # VQF's gyro bias estimate, body axes
    bias_y_rad_s: float
    bias_z_rad_s: float
    bias_std_rad_s: float  # its uncertainty
    mag_disturbed: float  # 1.0 when the magnetometer is judged disturbed (VQF's flag, 1.0 before any reading)


class Vqf(Estimator):
    """VQF (the package) behind the project's interface; built on the first sample's period."""

    name = "vqf"
    estimates_gyro_bias = True
    uses_magnetometer = True
    Settings = VqfSettings
    Diagnostics = VqfDiagnostics

    def _reset_state(self):
        self._filter = None  # vqf.VQF, made with the first sample's period
        self._mag_seen = False
        self._diag = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    def _make_filter(self, dt_s):
        s = self.settings
        self._filter = vqf_package.VQF(
            float(dt_s),
            tauAcc=s.tau_acc_s,
            tauMag=s.tau_mag_s,
            restBiasEstEnabled=bool(s.rest_bias_est),
            motionBiasEstEnabled=bool(s.motion_bias_est),
            magDistRejectionEnabled=bool(s.mag_dist_rejection),
        )

    def _set_attitude(self, q):
        self._q = q
        if self._filter is None:
            return  # VQF initialises itself from its first accelerometer sample, the same tilt
        # After a gap: restart VQF from q (its gyro quaternion), keeping its bias estimate.
        bias = self._filter.getBiasEstimate()[0]
        self._filter.resetState()
        self._filter.setBiasEstimate(bias, -1.0)
        state = self._filter.state
        state["gyrQuat"] = quaternion.multiply(quaternion.conjugate(self._frame()), q)
        self._filter.state = state

    def _frame(self):
        return _ENU_TO_NED if self._mag_seen else _UP_TO_DOWN

    def _diagnostics(self, status):
        return VqfDiagnostics(status, *self._diag)

    def _update(self, gx, gy, gz, ax, ay, az, acc_ok, dt_s, status):
        if self._filter is None:
            self._make_filter(dt_s)
        f = self._filter
        f.updateGyr(np.array((gx, gy, gz)))
        if acc_ok:
            f.updateAcc(np.array((ax, ay, az)) * STANDARD_GRAVITY_M_S2)
        mag = self._mag
        if mag is not None and all(math.isfinite(m) for m in mag):
            self._mag_seen = True
            f.updateMag(np.array(mag, dtype=float))
        q_vqf = f.getQuat9D() if self._mag_seen else f.getQuat6D()
        self._q = quaternion_product(self._frame(), q_vqf.tolist())
        bias, bias_std = f.getBiasEstimate()
        self._diag = (float(f.getRestDetected()), *bias.tolist(), float(bias_std), float(f.getMagDistDetected()))
        return self._q, VqfDiagnostics(status, *self._diag)

    @classmethod
    def runs_compiled(cls) -> bool:
        return _loaded(screen_rows, SCREEN_ROWS_SIGNATURE)

    def run(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """``updateBatch`` over each stretch of rows that ``step`` would give to VQF whole (module docstring),
        ``step``'s own code on the others: what stepping gives, bit for bit."""
        gyr, acc, dt = batch_inputs(gyr_rad_s, acc_g, dt_s)
        n = len(dt)
        mags = np.full((n, 3), np.nan) if mag is None else _rows(mag, n, 3, "mag")
        if gps is not None:
            _rows(gps, n, 4, "gps")  # checked like every estimator's; VQF does not use it
        guard = np.array([float(self._waiting), self._acc_dev, self._dt_run_s])
        params = np.array([self._acc_min2, self._acc_dev_max, self._acc_window_s, self._max_gap_s])
        status, dt_used = np.empty(n, dtype=np.int64), np.empty(n)
        _compiled(screen_rows, SCREEN_ROWS_SIGNATURE)(gyr, acc, dt, guard, params, status, dt_used)
        reading = np.isfinite(mags).all(axis=1)  # step's test for a reading
        # A row goes to the batch when step would update VQF with its gyro and accelerometer; the others
        # (held, re-initialised, accelerometer skipped, waiting) take step's code one at a time.
        whole = (status & (NO_UPDATE | ACC_SKIPPED)) == 0
        q, table = np.empty((n, 4)), np.empty((n, len(VqfDiagnostics._fields) - 1))
        edges = np.flatnonzero(np.diff(whole.astype(np.int8))) + 1
        for a, b in zip(np.r_[0, edges].tolist() if n else [], np.r_[edges, n].tolist()):
            if whole[a]:
                q[a:b], table[a:b] = self._batch(gyr[a:b], acc[a:b], mags[a:b], reading[a:b], status[a], dt_used[a])
            else:
                for k in range(a, b):
                    self._mag = tuple(mags[k].tolist()) if reading[k] else None
                    q[k], diag = self._screened(int(status[k]), not status[k] & ACC_SKIPPED, float(dt_used[k]), *gyr[k].tolist(), *acc[k].tolist())
                    table[k] = diag[1:]
        self._waiting, self._acc_dev, self._dt_run_s = bool(guard[0]), float(guard[1]), float(guard[2])
        return q, {"status": status} | {name: table[:, i] for i, name in enumerate(VqfDiagnostics._fields[1:])}

    def _batch(self, gyr, acc, mags, reading, first_status, first_dt_s):
        """A stretch of rows VQF takes whole: ``updateBatch``; rows without a reading get (0, 0, 0), which
        VQF skips as ``step`` skips the reading (its updateMag returns on a zero vector)."""
        if first_status & INITIALISED:
            self._waiting = False
            self._set_attitude(self._attitude_from_acc(*acc[0].tolist(), 0.0))
        if self._filter is None:
            self._make_filter(first_dt_s)
        seen = np.logical_or.accumulate(reading) | self._mag_seen  # per row: a reading has arrived
        with_mag = bool(seen[-1])
        out = self._filter.updateBatch(gyr, acc * STANDARD_GRAVITY_M_S2, np.where(reading[:, None], mags, 0.0) if with_mag else None)
        q6 = tuple(out["quat6D"].T)
        q = np.column_stack(quaternion_product(_UP_TO_DOWN, q6))
        if with_mag:
            q[seen] = np.column_stack(quaternion_product(_ENU_TO_NED, tuple(out["quat9D"].T)))[seen]
            self._mag_seen = True
        # without a reading VQF's flag stays as it was (set at its start), as step reads it every sample
        dist = out["magDistDetected"] if with_mag else np.full(len(gyr), self._filter.getMagDistDetected())
        table = np.column_stack([out["restDetected"], out["bias"], out["biasSigma"], dist]).astype(float)
        self._q = tuple(q[-1].tolist())
        self._diag = tuple(table[-1].tolist())
        return q, table

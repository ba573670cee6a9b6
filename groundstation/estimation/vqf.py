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

``run`` uses ``updateBatch`` (the loop in compiled code) when every sample is finite, has the same
sample period (within 1e-6 relative) and a usable accelerometer (and the windowed accelerometer gate
is off, its default here: VQF's low-pass already rides through disturbances), and the magnetometer is on every
sample or on none; otherwise it steps. Either way ``run`` gives what stepping gives (to rounding in the frame change).
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
import vqf as vqf_package

from groundstation import quaternion
from groundstation.estimation.base import INITIALISED, CommonSettings, Estimator
from groundstation.estimation.tilt import quaternion_product
from groundstation.units import STANDARD_GRAVITY_M_S2

_H = math.sqrt(0.5)
_ENU_TO_NED = (0.0, _H, _H, 0.0)
_UP_TO_DOWN = (0.0, 1.0, 0.0, 0.0)  # half turn about x: the 6D frame's z up becomes down
_PERIOD_RTOL = 1e-6


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
    mag_disturbed: float  # 1.0 when the magnetometer is judged disturbed (no reading: 0)


class Vqf(Estimator):
    """VQF (the package) behind the project's interface; built on the first sample's period."""

    name = "vqf"
    label = "VQF"
    colour = "orange"
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

    def run(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """``updateBatch`` when the data allow it (module docstring), else the stepping of ``Estimator.run``."""
        gyr = np.ascontiguousarray(gyr_rad_s, dtype=float).reshape(-1, 3)
        acc = np.ascontiguousarray(acc_g, dtype=float).reshape(-1, 3)
        dt = np.broadcast_to(np.asarray(dt_s, dtype=float), (len(gyr),))
        mags = None if mag is None else np.ascontiguousarray(mag, dtype=float).reshape(-1, 3)
        n2 = np.einsum("ij,ij->i", acc, acc) if len(acc) == len(gyr) else None
        batchable = (
            len(gyr) > 0
            and n2 is not None
            and np.all(np.isfinite(gyr))
            and not self._acc_gated
            and np.all((n2 >= self._acc_min2) & (n2 < math.inf))
            and np.all(np.abs(dt - dt[0]) <= _PERIOD_RTOL * dt[0])
            and 0.0 < dt[0] <= self._max_gap_s
            and (mags is None or np.all(np.isfinite(mags)) or (self._mag_seen is False and np.all(np.isnan(mags))))
            and (self._filter is None or abs(self._filter.coeffs["gyrTs"] - dt[0]) <= _PERIOD_RTOL * dt[0])
        )
        if not batchable:
            return super().run(gyr_rad_s, acc_g, dt_s, mag, gps)
        if mags is not None and not np.all(np.isfinite(mags)):
            mags = None  # all NaN: no magnetometer at all
        status = np.zeros(len(gyr), dtype=np.int64)
        if self._waiting:
            status[0] = INITIALISED
            self._waiting = False
        if self._filter is None:
            self._make_filter(dt[0])
        out = self._filter.updateBatch(gyr, acc * STANDARD_GRAVITY_M_S2, mags)
        if mags is not None:
            self._mag_seen = True
        q_vqf = out["quat9D"] if self._mag_seen else out["quat6D"]
        q = quaternion.multiply(np.array(self._frame()), q_vqf)
        dist = out["magDistDetected"].astype(float) if "magDistDetected" in out else np.zeros(len(gyr))
        diag = {
            "status": status,
            "rest": out["restDetected"].astype(float),
            "bias_x_rad_s": out["bias"][:, 0],
            "bias_y_rad_s": out["bias"][:, 1],
            "bias_z_rad_s": out["bias"][:, 2],
            "bias_std_rad_s": out["biasSigma"].astype(float),
            "mag_disturbed": dist,
        }
        self._q = tuple(q[-1].tolist())
        self._diag = tuple(float(diag[name][-1]) for name in VqfDiagnostics._fields[1:])
        return q, diag

"""What every estimator shares: settings, the robust per-sample ``step``, the batch ``run``.

Interface (the same for ``ahf``, ``hf``, ``ecf``, ``cf1``, ``kf`` and ``ekf``)::

    est = Ahf(AhfSettings(beta=...))          # settings: a frozen dataclass, defaults = the papers'
    est.reset(q0=None)                        # q0 None: initialise from the first accelerometer sample
    q, diag = est.step(gyr_rad_s, acc_g, dt_s)   # q = (w, x, y, z) body -> NED; diag a NamedTuple
    q_n4, diag_arrays = est.run(gyr_rad_s_n3, acc_g_n3, dt_s_n)   # exactly the numbers of step

``gyr_rad_s`` is the body-frame rate (x forward, y right, z down) in rad/s; ``acc_g`` the body-frame
specific force in g (standard gravity), so a level craft at rest reads about (0, 0, -1);
``dt_s`` is the time since the previous sample in seconds.

Aiding inputs, passed by every caller that has them and ignored by the estimators that do not use them
(the first six: their yaw is gyro-only and drifts):

- ``mag``: the magnetometer reading that arrived since the previous sample, on the body axes (x forward,
  y right, z down), µT; None when none did.
- ``gps``: the ``GpsFix`` that arrived since the previous sample, else None.

In ``run`` they are arrays: ``mag`` (N, 3) and ``gps`` (N, 4) = (vel_n, vel_e, vel_d m/s, heading rad),
a row of NaN meaning "none on this sample" (a NaN heading alone: a fix without heading).
Aiding estimators read them in ``_update`` as ``self._mag`` and ``self._gps``.

Robust stepping (every estimator, decided here once):

- The first sample whose accelerometer is usable sets pitch and roll from gravity (yaw 0), so no filter
  starts upside down; until then the output is the identity with ``WAITING`` set.
- NaN/Inf in the gyro or in ``dt_s``, or ``dt_s <= 0``: the sample is ignored, the previous estimate is
  returned unchanged (``HELD``).
- Accelerometer NaN/Inf, its norm below ``acc_min_g`` (free fall), or its norm's deviation from 1 g,
  low-passed over ``acc_window_s``, above ``acc_deviation_max_g`` (sustained shaking or acceleration):
  the gyro is integrated and the accelerometer correction skipped (``ACC_SKIPPED``). Why a low-passed
  deviation and not the instantaneous norm: under shaking the norm swings above and below 1 g, and
  rejecting only the large-norm half of each swing leaves a biased mean direction (BROAD trial 16, hf:
  12.4° with a 3 g limit, 3.0° without); the low-passed deviation ``|‖a‖ - 1|`` rejects both halves alike.
- ``dt_s > max_gap_s`` (seconds of lost frames): integrating one stale rate over the gap would be
  wrong, so pitch and roll are re-initialised from the accelerometer, keeping yaw (``REINITIALISED``);
  if the accelerometer is unusable too, the estimate is held.
- A gyro at its full-scale limit is a finite number and is integrated like any other (``ahf`` can
  also raise λ then; see its ``gyro_overrange_rad_s``).

Status flags are bits of ``diag.status`` (plain ints, cheap per sample).
"""

from __future__ import annotations

import dataclasses
import math
from itertools import chain
from typing import ClassVar, NamedTuple

import numpy as np

from groundstation import quaternion
from groundstation.estimation.tilt import acc_pitch_roll
from groundstation.readings import optional_rows

# diag.status bits
WAITING = 1  # no usable accelerometer sample yet; output is the identity
INITIALISED = 2  # attitude set from the accelerometer on this sample
HELD = 4  # bad gyro or dt: previous estimate returned unchanged
ACC_SKIPPED = 8  # accelerometer unusable: gyro-only on this sample
REINITIALISED = 16  # gap longer than max_gap_s: pitch/roll re-set from the accelerometer
GYRO_OVERRANGE = 32  # ahf only: gyro at or above gyro_overrange_rad_s, λ forced to λ_max



class GpsFix(NamedTuple):
    """One GPS solution as the attitude estimators use it: NED velocity and dual-antenna heading."""

    vel_n_m_s: float
    vel_e_m_s: float
    vel_d_m_s: float
    heading_rad: float  # true heading of the antenna baseline (yaw), NaN when the receiver gives none


STATUS_NAMES = {
    WAITING: "waiting",
    INITIALISED: "initialised",
    HELD: "held",
    ACC_SKIPPED: "acc_skipped",
    REINITIALISED: "reinitialised",
    GYRO_OVERRANGE: "gyro_overrange",
}


@dataclasses.dataclass(frozen=True)
class CommonSettings:
    """Input guards shared by every estimator (see the module docstring)."""

    acc_min_g: float = 0.2  # below: free fall, the accelerometer says nothing about gravity
    # Sustained disturbance: the low-passed |‖acc‖ - 1 g| (time constant acc_window_s) above this skips
    # the accelerometer. Chosen on the BROAD dev set (bench/bench_estimators.out.md).
    acc_deviation_max_g: float = math.inf
    acc_window_s: float = 1.0
    max_gap_s: float = 1.0  # longer dt: re-initialise from the accelerometer instead of integrating


class Estimator:
    """Base class; subclasses set ``name``, ``Settings``, ``Diagnostics`` and implement the hooks.

    Hooks: ``_reset_state()``, ``_set_attitude(q)`` (q a unit quaternion tuple), ``_update(gx, gy, gz,
    ax, ay, az, acc_ok, dt_s, status) -> (q, diag)``, ``_diagnostics(status) -> diag`` (for held
    samples), and the ``_q`` attribute holding the current output tuple.
    """

    name: ClassVar[str]
    # True when the filter estimates its own gyro bias; the session applies a bias measured at rest
    # (calibration.RestBiasCalibrator) only to the others
    estimates_gyro_bias: ClassVar[bool] = False
    _cast = None  # a numpy scalar type to run in (ahf/hf: dtype=np.float32); None = Python floats
    Settings: ClassVar[type]
    Diagnostics: ClassVar[type[NamedTuple]]

    def __init__(self, settings=None):
        self.settings = self.Settings() if settings is None else settings
        s = self.settings
        if not 0.0 <= s.acc_min_g < 1.0 or not s.acc_deviation_max_g > 0.0 or not s.acc_window_s > 0.0:
            raise ValueError("need 0 <= acc_min_g < 1, acc_deviation_max_g > 0 and acc_window_s > 0")
        if not s.max_gap_s > 0.0:  # a gap of any length would re-initialise: the estimator would never integrate
            raise ValueError(f"max_gap_s must be positive (seconds), not {s.max_gap_s}")
        self._acc_min2 = s.acc_min_g * s.acc_min_g
        self._acc_dev_max = s.acc_deviation_max_g
        self._acc_gated = s.acc_deviation_max_g != math.inf
        self._acc_window_s = s.acc_window_s
        self._max_gap_s = s.max_gap_s
        self.reset()

    # -- public interface -------------------------------------------------------------------

    def reset(self, q0=None) -> None:
        """Forget the past. ``q0`` (w, x, y, z) starts from that attitude instead of waiting for gravity."""
        self._reset_state()
        self._acc_dev = 0.0  # low-passed |‖acc‖ - 1| (g)
        if q0 is None:
            self._q = (1.0, 0.0, 0.0, 0.0)
            self._waiting = True
        else:
            self._set_attitude(tuple(quaternion.normalise(q0).tolist()))
            self._waiting = False

    def step(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """One sample: returns ``(q, diag)``, q = (w, x, y, z) rotating body vectors into NED."""
        self._mag = mag
        self._gps = gps
        gx, gy, gz = gyr_rad_s
        ax, ay, az = acc_g
        if self._cast is not None:
            c = self._cast
            gx, gy, gz, ax, ay, az, dt_s = c(gx), c(gy), c(gz), c(ax), c(ay), c(az), c(dt_s)
        n2 = ax * ax + ay * ay + az * az
        # NaN fails every comparison, so this one test rejects NaN, Inf and free fall.
        acc_ok = self._acc_min2 <= n2 < math.inf
        # Only a finite positive dt weighs the deviation: inf would make it inf/inf = NaN for good.
        if acc_ok and self._acc_gated and 0.0 < dt_s < math.inf:
            dev = self._acc_dev
            dev += (abs(n2**0.5 - 1.0) - dev) * dt_s / (self._acc_window_s + dt_s)
            self._acc_dev = dev
            acc_ok = dev <= self._acc_dev_max
        status = 0
        if self._waiting:
            if not acc_ok:
                return self._q, self._diagnostics(WAITING)
            self._set_attitude(self._attitude_from_acc(ax, ay, az, 0.0))
            self._waiting = False
            status = INITIALISED
        total = gx + gy + gz + dt_s
        if not dt_s > 0.0 or total - total != 0.0:  # dt <= 0, or a NaN/Inf anywhere in gyro or dt
            return self._q, self._diagnostics(status | HELD)
        if dt_s > self._max_gap_s:
            if not acc_ok:
                return self._q, self._diagnostics(status | HELD)
            yaw = float(quaternion.to_euler_zyx(np.array(self._q, dtype=float))[0])
            self._set_attitude(self._attitude_from_acc(ax, ay, az, yaw))
            return self._q, self._diagnostics(status | REINITIALISED)
        if not acc_ok:
            status |= ACC_SKIPPED
        return self._update(gx, gy, gz, ax, ay, az, acc_ok, dt_s, status)

    def run(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """Step through arrays: gyr_rad_s and acc_g (N, 3), dt_s (N,) or a scalar; mag (N, 3) and gps
        (N, 4) optional, NaN rows for samples without a reading (see the module docstring).

        Continues from the current state (call ``reset()`` first for a fresh start). Returns
        ``(q, diag)``: q an (N, 4) float64 array, diag a dict of (N,) arrays, one per diagnostics field;
        row k is exactly what ``step`` returns for sample k.
        """
        gyr = np.asarray(gyr_rad_s, dtype=float).reshape(-1, 3)
        acc = np.asarray(acc_g, dtype=float).reshape(-1, 3)
        dt = np.broadcast_to(np.asarray(dt_s, dtype=float), (len(gyr),))
        if len(acc) != len(gyr):
            raise ValueError(f"gyr_rad_s has {len(gyr)} rows but acc_g has {len(acc)}")
        mags = optional_rows(mag, len(gyr), 3, "mag")
        fixes = [None if r is None else GpsFix(*r) for r in optional_rows(gps, len(gyr), 4, "gps")]
        step = self.step
        qs, diags = [], []
        # tolist(): plain Python floats, the fast path of step.
        for g, a, d, m, f in zip(gyr.tolist(), acc.tolist(), dt.tolist(), mags, fixes):
            q, diag = step(g, a, d, m, f)
            qs.append(q)
            diags.append(diag)
        fields = self.Diagnostics._fields
        # fromiter over the flattened rows: ~10x faster than np.array on a list of NamedTuples.
        q = np.fromiter(chain.from_iterable(qs), float, count=4 * len(qs)).reshape(-1, 4)
        table = np.fromiter(chain.from_iterable(diags), float, count=len(fields) * len(diags))
        table = table.reshape(-1, len(fields))
        diag = {name: table[:, i] for i, name in enumerate(fields)}
        diag["status"] = diag["status"].astype(np.int64)  # exact: flags < 2**53
        return q, diag

    # -- shared helpers ---------------------------------------------------------------------

    @staticmethod
    def _attitude_from_acc(ax, ay, az, yaw_rad):
        """Quaternion with the given yaw whose pitch and roll put gravity where the accelerometer says."""
        pitch, roll = acc_pitch_roll(float(ax), float(ay), float(az))
        return tuple(quaternion.from_euler_zyx(yaw_rad, pitch, roll).tolist())


def integrate_rate(q, wx, wy, wz, dt_s):
    """``q + ½ q ⊗ [0, ω] dt``, normalised: one Euler step of the attitude kinematics (seed 000 eq. 6, 19)."""
    q1, q2, q3, q4 = q
    h = 0.5 * dt_s
    q1, q2, q3, q4 = (
        q1 - h * (q2 * wx + q3 * wy + q4 * wz),
        q2 + h * (q1 * wx + q3 * wz - q4 * wy),
        q3 + h * (q1 * wy - q2 * wz + q4 * wx),
        q4 + h * (q1 * wz + q2 * wy - q3 * wx),
    )
    r = (q1 * q1 + q2 * q2 + q3 * q3 + q4 * q4) ** -0.5
    return (q1 * r, q2 * r, q3 * r, q4 * r)

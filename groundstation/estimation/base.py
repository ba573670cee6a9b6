"""What every estimator shares: settings, the robust per-sample ``step``, the batch ``run``.

Interface (the same for every estimator of ``ESTIMATORS``)::

    est = Ahf(AhfSettings(beta=...))          # settings: a frozen dataclass, defaults = the papers'
    est.reset(q0=None)                        # q0 None: initialise from the first accelerometer sample
    q, diag = est.step(gyr_rad_s, acc_g, dt_s, mag, gps)   # q = (w, x, y, z) body -> NED; diag a NamedTuple
    q_n4, diag_arrays = est.run(gyr_rad_s_n3, acc_g_n3, dt_s_n, mag_n3, gps_n4)   # exactly the numbers of step

``mag`` and ``gps`` (None, or NaN where a sample has no reading) reach the estimators that use them
(a magnetometer: ``hfm``, ``ecfm``, ``mcf``; GPS velocity and heading: ``ukf``, ``sssrukf``); the others ignore them.

``gyr_rad_s`` is the body-frame rate (x forward, y right, z down) in rad/s; ``acc_g`` the body-frame
specific force in g (standard gravity), so a level craft at rest reads about (0, 0, -1);
``dt_s`` is the time since the previous sample in seconds.

Aiding inputs, passed by every caller that has them and ignored by the estimators that do not use them
(their yaw is gyro-only and drifts); ``needs`` names those an estimator is little without:

- ``mag``: the magnetometer reading that arrived since the previous sample, on the body axes (x forward,
  y right, z down), µT; None when none did.
- ``gps``: the ``GpsFix`` that arrived since the previous sample, else None.

In ``run`` they are arrays: ``mag`` (N, 3) and ``gps`` (N, 4) = (vel_n, vel_e, vel_d m/s, heading rad),
a row of NaN meaning "none on this sample" (a NaN heading alone: a fix without heading).
Aiding estimators read them in ``_update`` as ``self._mag`` and ``self._gps``.

Robust stepping (every estimator, decided here once):

- The first sample whose accelerometer is usable sets pitch and roll from gravity (yaw 0), so no filter
  starts upside down; until then the output is the identity with ``WAITING`` set.
- The interval rule, for every estimator (this guard, and the C core's gs_ahf.c mirrors it):

  - NaN/Inf in the gyro or in ``dt_s``, or ``dt_s <= 0`` (a repeated or reordered sample, a clock jump
    back): the sample is ignored, the previous estimate is returned unchanged (``HELD``).
  - ``dt_s > max_gap_s`` (seconds of lost frames): pitch and roll are re-initialised from the accelerometer,
    yaw kept (``REINITIALISED``); if the accelerometer is unusable too, the estimate is held.
  - Otherwise one step integrates at most ``STEP_RATIO_MAX`` (1.5) running intervals: a longer ``dt_s``
    (a radio dropout, a logger stall) is integrated as that (``LIMITED``). The running interval is the
    first integrated ``dt_s``, then a low-pass (weight ``INTERVAL_WEIGHT``) of the integrated ones: it
    follows a rate that rises (4 Hz, then 50 Hz) within a few samples, and one that falls by 1/8 a sample
    (from 50 Hz to 4 Hz in about 20 samples, which meanwhile integrate less than their whole interval).

  Why a limit and not one step over the whole interval: the corrections are Euler steps whose size grows
  with Δt — seed 000 eq. 19, ``q(k) = q(k-1) + q̇ Δt`` with eq. 18's normalised gradient, turns the
  estimate by λ Δt whatever the error, so one 0.161 s sample at λ = 2 rad/s turned a still AHF 32°
  (121° for 1 s), and HF (λ = β) 1.9°; a Kalman or complementary gain ``Δt/(τ + Δt)`` saturates likewise.
  Why not sub-steps over the interval: they would repeat one sample's gyro and accelerometer over time
  nobody measured, so the accelerometer would pull as if seen for the whole gap; and the rate during the
  gap is unknown, so the lost part of it is not integrated either (VQF, the reference, integrates every
  sample over its fixed period alike). The step keeps eq. 19's form, with Δt at most 1.5 running
  intervals; the paper's eq. 20 (AHF's λ) is unchanged. Why 1.5: intervals jittering by up to half
  the period pass unchanged, while AHF at rest (λ Δt ≈ 2° a sample at 100 Hz) gains 0.4° of tilt error
  from a limited step (1.4° with a limit of 2). On still data no interval moves any
  estimator's tilt by more than 1° (tests/estimation/test_intervals.py, every registered estimator).
- Accelerometer NaN/Inf, its norm below ``acc_min_g`` (free fall), or its norm's deviation from 1 g,
  low-passed over ``acc_window_s``, above ``acc_deviation_max_g`` (sustained shaking or acceleration):
  the gyro is integrated and the accelerometer correction skipped (``ACC_SKIPPED``). Why a low-passed
  deviation and not the instantaneous norm: under shaking the norm swings above and below 1 g, and
  rejecting only the large-norm half of each swing leaves a biased mean direction (BROAD trial 16, hf:
  12.4° with a 3 g limit, 3.0° without); the low-passed deviation ``|‖a‖ - 1|`` rejects both halves alike.
- A magnetometer estimator corrects heading only, and not with a reading whose norm or dip is off the
  field it has learnt (``field_screen``: a magnet near the sensor, a motor's current; ``MAG_REJECTED``).
- A gyro at its full-scale limit is a finite number and is integrated like any other (``ahf`` can
  also raise λ then; see its ``gyro_overrange_rad_s``).

Status flags are bits of ``diag.status`` (plain ints, cheap per sample).

Compiled estimators (``CompiledEstimator``: ahf, ahf2, ahf2m, hf, ecf, cf1, kf, ekf, hfm, ecfm, mcf, ukf, sssrukf): each one's
per-sample arithmetic is written once, as a ``kernel(state, params, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz)
-> status`` on scalars and two small float arrays (a GPS-aided one, ``gps_aided``, takes the fix's
``vel_n, vel_e, vel_d, heading`` after the magnetometer's, NaN for none), that starts with this module's
``guard``. numba compiles
it; ``step`` calls it once per sample, ``run`` calls it in a compiled loop (the estimator's
``run_kernel``), so the two agree sample for sample by construction (2-6 µs a step, millions of samples a second
in ``run``; bench/bench_kernels.out.md). ``state`` holds q, the waiting flag, the gate's deviation, the
running interval, the diagnostics after ``status`` in their order, then the estimator's own state; ``params`` the guard's
settings, then the estimator's (``STATE_*``, ``P_*`` below). The helpers a kernel calls are
``register_jitable``: compiled inside a kernel, plain Python when called from Python, so the same source
also runs interpreted on numpy.float32 numbers (``dtype=np.float32``: ahf's onboard firmware model, bit
for bit with the C core) or float64 (tests compare it with the compiled code).

Why numba: the filters are scalar recurrences (each sample needs the previous state), which numpy
cannot vectorise; numba compiles this Python source nearly unchanged, so one source serves the compiled
and the interpreted path, and it installs from wheels (Windows, Linux, macOS) with no compiler on the
user's machine, where Cython or a C extension would need one or a wheel per platform built by us.
Its cost is compiling: ``cache=True`` writes the machine code beside the sources (``__pycache__``) on
the first use on a machine, and each kernel is compiled lazily, when its estimator is first created, so
a command that uses none pays nothing (figures in bench/bench_kernels.out.md); a live session never waits
for it: until another process has put a kernel in the cache, its estimator runs the kernel's source
interpreted (``ready_or_interpreted``, ``take_compiled``; ``estimation.warm_up``). numba checks a cached
function against its own file only, so ``drop_stale_cache`` drops a kernel's cache when this module,
``tilt`` or ``compass`` (compiled into every kernel) is newer (tests/estimation/test_kernels.py also
compares the compiled kernels with their interpreted source).
"""

from __future__ import annotations

import dataclasses
import math
import threading
from itertools import chain
from pathlib import Path
from typing import ClassVar, NamedTuple

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload, register_jitable

from groundstation import quaternion
from groundstation.estimation import compass, tilt
from groundstation.estimation.compass import level_heading_rad
from groundstation.estimation.tilt import acc_pitch_roll, euler_of, quaternion_of, wrap_pi
from groundstation.readings import optional_rows

# diag.status bits
WAITING = 1  # no usable accelerometer sample yet; output is the identity
INITIALISED = 2  # attitude set from the accelerometer on this sample
HELD = 4  # bad gyro or dt: previous estimate returned unchanged
ACC_SKIPPED = 8  # accelerometer unusable: gyro-only on this sample
REINITIALISED = 16  # gap longer than max_gap_s: pitch/roll re-set from the accelerometer
GYRO_OVERRANGE = 32  # ahf only: gyro at or above gyro_overrange_rad_s, λ forced to λ_max
LIMITED = 64  # dt above STEP_RATIO_MAX running intervals: integrated as that many (the interval rule)
MAG_REJECTED = 128  # magnetometer estimators: the reading disagrees with the learnt field, heading not corrected (field_screen)
NO_UPDATE = WAITING | HELD | REINITIALISED  # the guard has said all there is to say about the sample


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
    LIMITED: "limited",
    MAG_REJECTED: "mag_rejected",
}

# The interval rule (module docstring): a step integrates at most STEP_RATIO_MAX running intervals; the
# running interval follows each (limited) dt with this weight.
STEP_RATIO_MAX = 1.5
INTERVAL_WEIGHT = 0.25


@dataclasses.dataclass(frozen=True)
class CommonSettings:
    """Input guards shared by every estimator (see the module docstring)."""

    acc_min_g: float = 0.2  # below: free fall, the accelerometer says nothing about gravity
    # Sustained disturbance: the low-passed |‖acc‖ - 1 g| (time constant acc_window_s) above this skips
    # the accelerometer. Chosen on the BROAD dev set (bench/bench_estimators.out.md).
    acc_deviation_max_g: float = math.inf
    acc_window_s: float = 1.0
    max_gap_s: float = 1.0  # longer dt: re-initialise from the accelerometer instead of integrating


@register_jitable
def screen(gx, gy, gz, ax, ay, az, dt_s, waiting, acc_dev, dt_run_s, acc_min2, acc_dev_max, acc_window_s, max_gap_s):
    """The input guard of the module docstring: ``(status, acc_ok, acc_dev, dt_s, dt_run_s)``, acc_dev the
    new low-passed deviation, dt_s the interval to integrate and dt_run_s the new running interval (0:
    none yet). The caller sets the attitude from gravity on ``INITIALISED``, then on ``REINITIALISED``
    (yaw kept), and updates the filter with that dt_s unless ``status & NO_UPDATE``."""
    n2 = ax * ax + ay * ay + az * az
    # NaN fails every comparison, so this one test rejects NaN, Inf and free fall.
    acc_ok = acc_min2 <= n2 and n2 < math.inf
    # Only a finite positive dt weighs the deviation: inf would make it inf/inf = NaN for good.
    if acc_ok and acc_dev_max < math.inf and 0.0 < dt_s and dt_s < math.inf:
        # np.sqrt, not ** 0.5: correctly rounded in every type, as the C core's sqrtf (ahf.py's docstring)
        acc_dev += (abs(np.sqrt(n2) - 1.0) - acc_dev) * dt_s / (acc_window_s + dt_s)
        acc_ok = acc_dev <= acc_dev_max
    status = 0
    if waiting:
        if not acc_ok:
            return WAITING, acc_ok, acc_dev, dt_s, dt_run_s
        status = INITIALISED
    total = gx + gy + gz + dt_s
    if not dt_s > 0.0 or total - total != 0.0:  # dt <= 0, or a NaN/Inf anywhere in gyro or dt
        return status | HELD, acc_ok, acc_dev, dt_s, dt_run_s
    if dt_s > max_gap_s:  # re-initialise from gravity; without it there is nothing to go on: held
        return status | (REINITIALISED if acc_ok else HELD), acc_ok, acc_dev, dt_s, dt_run_s
    if not acc_ok:
        status |= ACC_SKIPPED
    if dt_run_s == 0.0:  # the first interval integrated sets the running one
        dt_run_s = dt_s
    limit_s = STEP_RATIO_MAX * dt_run_s
    if dt_s > limit_s:
        dt_s = limit_s
        status |= LIMITED
    dt_run_s = dt_run_s + (dt_s - dt_run_s) * INTERVAL_WEIGHT
    return status, acc_ok, acc_dev, dt_s, dt_run_s


@njit(cache=True)
def screen_rows(gyr, acc, dt, guard_state, params, status_out, dt_out):
    """``screen`` over ``run``'s rows (an estimator whose filter runs in a batch of its own, vqf): each
    row's status and the interval it integrates; ``guard_state`` (waiting, acc_dev, dt_run_s) is carried
    through as ``step`` carries it, ``params`` (acc_min2, acc_dev_max, acc_window_s, max_gap_s)."""
    waiting, acc_dev, dt_run_s = guard_state[0] != 0.0, guard_state[1], guard_state[2]
    for k in range(dt.shape[0]):
        status, _, acc_dev, dt_out[k], dt_run_s = screen(
            gyr[k, 0], gyr[k, 1], gyr[k, 2], acc[k, 0], acc[k, 1], acc[k, 2], dt[k], waiting, acc_dev, dt_run_s, params[0], params[1], params[2], params[3]
        )
        if status & INITIALISED:
            waiting = False
        status_out[k] = status
    guard_state[0], guard_state[1], guard_state[2] = 1.0 if waiting else 0.0, acc_dev, dt_run_s


@register_jitable
def gravity_attitude(ax, ay, az, yaw_rad):
    """Quaternion (tuple) with the given yaw whose pitch and roll put gravity where the accelerometer says."""
    pitch, roll = acc_pitch_roll(ax, ay, az)
    return quaternion_of(yaw_rad, pitch, roll)


@register_jitable
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


class Estimator:
    """Base class; subclasses set ``name``, ``label``, ``colour``, ``Settings``, ``Diagnostics`` (and ``needs``
    when they use aiding) and implement the hooks.

    Hooks: ``_reset_state()``, ``_set_attitude(q)`` (q a unit quaternion tuple), ``_update(gx, gy, gz,
    ax, ay, az, acc_ok, dt_s, status) -> (q, diag)``, ``_diagnostics(status) -> diag`` (for held
    samples), and the ``_q`` attribute holding the current output tuple.
    """

    name: ClassVar[str]
    # How the estimator describes itself to the app, evaluate and exports (``ESTIMATORS`` lists the classes;
    # a built-in one's from ``estimation.BUILT_IN``, see ``__init_subclass__``):
    label: ClassVar[str]  # what the legend, the panel and the charts call it
    colour: ClassVar[str]  # a colour's name in the app's palette (``groundstation.palette.PALETTE``): Qt stays out of here
    needs: ClassVar[frozenset[str]] = frozenset()  # aiding it is no more than a tilt filter without: "mag", "gps"
    live: ClassVar[bool] = True  # run on every live session (so showing it is a click, not a restart)
    tunable: ClassVar[tuple[tuple[str, str, str], ...]] = ()  # settings the app offers to tune live: (setting, symbol, unit)
    # True when the filter estimates its own gyro bias; the session applies a bias measured at rest
    # (calibration.RestBiasCalibrator) only to the others
    estimates_gyro_bias: ClassVar[bool] = False
    # True when its heading comes from the magnetometer when it has readings (evaluate scores that heading)
    uses_magnetometer: ClassVar[bool] = False
    Settings: ClassVar[type]
    Diagnostics: ClassVar[type[NamedTuple]]

    def __init_subclass__(cls, **kwargs):
        """A built-in estimator's label, colour, needs, live flag and tunable settings are written once, in
        the registry (``estimation.BUILT_IN``), which knows them without importing this module's numba."""
        super().__init_subclass__(**kwargs)
        from groundstation.estimation import BUILT_IN

        facts = BUILT_IN.get(cls.__dict__.get("name"))
        if facts is not None and facts.class_name == cls.__name__:
            cls.label, cls.colour, cls.needs, cls.live, cls.tunable = facts.label, facts.colour, facts.needs, facts.live, facts.tunable

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
        self._dt_run_s = 0.0  # the running sample interval (the interval rule); 0: none yet
        if q0 is None:
            self._q = (1.0, 0.0, 0.0, 0.0)
            self._waiting = True
        else:
            self._set_attitude(tuple(quaternion.normalise(q0).tolist()))
            self._waiting = False

    @classmethod
    def ready_or_interpreted(cls, settings=None) -> Estimator:
        """The estimator, never waiting for a compiler (``CompiledEstimator``'s may run interpreted at first)."""
        return cls(settings)

    interpreted = False  # running an interpreted kernel until ``take_compiled``

    @classmethod
    def runs_compiled(cls) -> bool:
        """Whether ``run`` over a file starts at once: what it compiles is compiled or in numba's cache (never
        compiles here; ``_loaded``). A file opened in the app runs those that do and leaves the others to
        another process (``session_makers.load.Loading``)."""
        return True

    def take_compiled(self) -> bool:
        """Go on compiled once the kernel is (``CompiledEstimator``); whether it runs compiled now."""
        return True

    def restart(self, q0=None) -> None:
        """After the sensor's board restarted (its gyro offset may have changed): forget what was learnt of
        the sensors, keep the attitude ``q0``, the estimator's last one (None: wait for gravity). Most
        estimators hold nothing else worth keeping, so this is ``reset(q0)``; one whose attitude rests on
        more state (a low-pass of the accelerometer) overrides it."""
        self.reset(q0)

    def step(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """One sample: returns ``(q, diag)``, q = (w, x, y, z) rotating body vectors into NED."""
        self._mag = mag
        self._gps = gps
        gx, gy, gz = gyr_rad_s
        ax, ay, az = acc_g
        status, acc_ok, self._acc_dev, dt_s, self._dt_run_s = screen(
            gx, gy, gz, ax, ay, az, dt_s, self._waiting, self._acc_dev, self._dt_run_s, self._acc_min2, self._acc_dev_max, self._acc_window_s, self._max_gap_s
        )
        return self._screened(status, acc_ok, dt_s, gx, gy, gz, ax, ay, az)

    def _screened(self, status, acc_ok, dt_s, gx, gy, gz, ax, ay, az):
        """The rest of ``step`` once ``screen`` has judged the sample (and updated the guard's state)."""
        if status & INITIALISED:
            self._waiting = False
            self._set_attitude(self._attitude_from_acc(ax, ay, az, 0.0))
        if status & REINITIALISED:
            self._set_attitude(self._attitude_from_acc(ax, ay, az, euler_of(self._q)[0]))
        if status & NO_UPDATE:
            return self._q, self._diagnostics(status)
        return self._update(gx, gy, gz, ax, ay, az, acc_ok, dt_s, status)

    def run(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        """Step through arrays: gyr_rad_s and acc_g (N, 3), dt_s (N,) or a scalar; mag (N, 3) and gps
        (N, 4) optional, NaN rows for samples without a reading (see the module docstring).

        Continues from the current state (call ``reset()`` first for a fresh start). Returns
        ``(q, diag)``: q an (N, 4) float64 array, diag a dict of (N,) arrays, one per diagnostics field;
        row k is exactly what ``step`` returns for sample k.
        """
        gyr, acc, dt = batch_inputs(gyr_rad_s, acc_g, dt_s)
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
        return gravity_attitude(float(ax), float(ay), float(az), float(yaw_rad))


def batch_inputs(gyr_rad_s, acc_g, dt_s):
    """``run``'s arrays as contiguous float64: gyr and acc (N, 3), dt (N,); ValueError on unequal lengths.
    Writable too (a copy of a read-only array): the compiled loop's signature is for writable arrays."""
    gyr = _rows(gyr_rad_s, None, 3, "gyr_rad_s")
    acc = _rows(acc_g, len(gyr), 3, "acc_g")
    return gyr, acc, np.require(np.broadcast_to(np.asarray(dt_s, dtype=float), (len(gyr),)), requirements="CW")


# -- compiled estimators (module docstring) ---------------------------------------------------

# Slots of a compiled estimator's state array
STATE_WAITING = 4  # state[0:4] is q (w, x, y, z); this slot 1 while waiting for gravity, else 0
STATE_ACC_DEV = 5  # the low-passed |‖acc‖ - 1| (g)
STATE_DT_RUN = 6  # the running sample interval, s (the interval rule); 0 before the first
STATE_MAG = 7  # field_screen's: the reference field's norm (0: none yet) and dip, the candidate's norm, dip and time
STATE_DIAG = 12  # the diagnostics after status, in their order; then the estimator's own state
# Slots of its parameter array
P_ACC_MIN2, P_ACC_DEV_MAX, P_ACC_WINDOW_S, P_MAX_GAP_S = 0, 1, 2, 3
P_MAGNETOMETER = 4  # 1: the estimator uses the magnetometer (marg.py): yaw from the compass on (re-)initialising
P_OWN = 5  # the estimator's own parameters

_F8, _VECTOR, _ROWS = types.float64, types.float64[::1], types.float64[:, ::1]
KERNEL_SIGNATURE = types.int64(_VECTOR, _VECTOR, *[_F8] * 10)  # state, params, gyr, acc, dt_s, mag
RUN_SIGNATURE = types.void(_VECTOR, _VECTOR, _ROWS, _ROWS, _VECTOR, _ROWS, _ROWS, types.int64[::1], _ROWS)  # (state, params, gyr, acc, dt, mag, outputs)
# A GPS-aided kernel (``gps_aided``) takes the fix's four numbers after the magnetometer's, its run loop
# the (N, 4) rows after the magnetometer's
GPS_KERNEL_SIGNATURE = types.int64(_VECTOR, _VECTOR, *[_F8] * 14)
SCREEN_ROWS_SIGNATURE = types.void(_ROWS, _ROWS, _VECTOR, _VECTOR, _VECTOR, types.int64[::1], _VECTOR)  # screen_rows
GPS_RUN_SIGNATURE = types.void(_VECTOR, _VECTOR, _ROWS, _ROWS, _VECTOR, _ROWS, _ROWS, _ROWS, types.int64[::1], _ROWS)


@register_jitable
def _set_gravity_attitude(state, p, ax, ay, az, yaw_rad, mx, my, mz):
    """state[0:4] from gravity with this yaw, or the compass's (``P_MAGNETOMETER``, a usable reading).
    In double, whatever the state's type (the C core's set_from_gravity)."""
    ax, ay, az = float(ax), float(ay), float(az)
    n2 = mx * mx + my * my + mz * mz
    if p[P_MAGNETOMETER] != 0.0 and 0.0 < n2 and n2 < math.inf:
        pitch, roll = acc_pitch_roll(ax, ay, az)
        yaw_rad = wrap_pi(level_heading_rad(pitch, roll, mx, my, mz))
    state[0], state[1], state[2], state[3] = gravity_attitude(ax, ay, az, yaw_rad)


@register_jitable
def guard(state, p, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz):
    """``screen`` on a compiled estimator's state, the attitude set as it says: ``(status, acc_ok, dt_s)``,
    dt_s the interval the kernel integrates (the interval rule)."""
    status, acc_ok, acc_dev, dt_s, dt_run_s = screen(
        gx, gy, gz, ax, ay, az, dt_s, state[STATE_WAITING] != 0.0, state[STATE_ACC_DEV], state[STATE_DT_RUN],
        p[P_ACC_MIN2], p[P_ACC_DEV_MAX], p[P_ACC_WINDOW_S], p[P_MAX_GAP_S]
    )
    state[STATE_ACC_DEV] = acc_dev
    state[STATE_DT_RUN] = dt_run_s
    if status & INITIALISED:
        state[STATE_WAITING] = 0.0
        _set_gravity_attitude(state, p, ax, ay, az, 0.0, mx, my, mz)
    if status & REINITIALISED:
        yaw = euler_of((float(state[0]), float(state[1]), float(state[2]), float(state[3])))[0]
        _set_gravity_attitude(state, p, ax, ay, az, yaw, mx, my, mz)
    return status, acc_ok, dt_s


# Magnetic disturbance rejection (field_screen), VQF's rule and constants (Laidig & Seel 2023, §3.3; Fusion's
# magnetic rejection is alike): a reading whose norm or dip is off the learnt reference is a disturbance
MAG_NORM_TOLERANCE = 0.1  # |‖m‖ - n_ref| above this fraction of n_ref
MAG_DIP_TOLERANCE_RAD = math.radians(10.0)  # |dip - dip_ref| above this
MAG_REF_TAU_S = 20.0  # the reference follows the accepted readings with this time constant
MAG_NEW_S = 20.0  # a steady other field seen this long while turning becomes the reference
MAG_NEW_RATE_RAD_S = math.radians(20.0)  # "while turning": an external field stays steady in norm and dip only if earth-fixed


@register_jitable
def _matches(n, dip, n_ref, dip_ref):
    return abs(n - n_ref) <= MAG_NORM_TOLERANCE * n_ref and abs(dip - dip_ref) <= MAG_DIP_TOLERANCE_RAD


@register_jitable
def field_screen(state, status, gx, gy, gz, dt_s, mx, my, mz):
    """Whether a magnetometer estimator may correct heading with this reading: ``(status, usable)``, status
    with ``MAG_REJECTED`` when the reading's norm or dip (its angle below the estimated horizontal) is off
    the learnt reference (a magnet, a motor's current). The first reading sets the reference; accepted
    readings move it slowly (``MAG_REF_TAU_S``); another field steady in norm and dip for ``MAG_NEW_S``
    of turning becomes it (the reference was the disturbed one, or the craft has moved). Not usable
    without a reading (None, NaN, zero), which is no rejection."""
    n2 = mx * mx + my * my + mz * mz
    if not (0.0 < n2 and n2 < math.inf):
        return status, False
    q1, q2, q3, q4 = state[0], state[1], state[2], state[3]
    n = math.sqrt(n2)
    # down on the body axes (seed 000 eq. 8) against the reading's direction
    s = (2.0 * (q2 * q4 - q1 * q3) * mx + 2.0 * (q1 * q2 + q3 * q4) * my + (q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4) * mz) / n
    dip = math.asin(min(max(s, -1.0), 1.0))
    if state[STATE_MAG] == 0.0:
        state[STATE_MAG], state[STATE_MAG + 1] = n, dip
        return status, True
    k = dt_s / (MAG_REF_TAU_S + dt_s)
    if _matches(n, dip, state[STATE_MAG], state[STATE_MAG + 1]):
        state[STATE_MAG] += k * (n - state[STATE_MAG])
        state[STATE_MAG + 1] += k * (dip - state[STATE_MAG + 1])
        state[STATE_MAG + 2] = state[STATE_MAG + 4] = 0.0  # no candidate
        return status, True
    if state[STATE_MAG + 2] == 0.0 or not _matches(n, dip, state[STATE_MAG + 2], state[STATE_MAG + 3]):
        state[STATE_MAG + 2], state[STATE_MAG + 3], state[STATE_MAG + 4] = n, dip, 0.0  # a new candidate
    else:
        state[STATE_MAG + 2] += k * (n - state[STATE_MAG + 2])
        state[STATE_MAG + 3] += k * (dip - state[STATE_MAG + 3])
        if gx * gx + gy * gy + gz * gz >= MAG_NEW_RATE_RAD_S * MAG_NEW_RATE_RAD_S:
            state[STATE_MAG + 4] += dt_s
        if state[STATE_MAG + 4] >= MAG_NEW_S:
            state[STATE_MAG], state[STATE_MAG + 1] = state[STATE_MAG + 2], state[STATE_MAG + 3]
            state[STATE_MAG + 2] = state[STATE_MAG + 4] = 0.0
            return status, True
    return status | MAG_REJECTED, False


def unmanaged(array):
    """``array`` as a compiled kernel's run loop works on it: the same memory, without numba's reference count
    (a view of an unmanaged array is unmanaged too). Every view a kernel takes of its state (a slice, a
    reshape: ukf's matrices) and every array it passes to a helper counts a reference up and down, an atomic
    instruction each (~10 ns); ukf spent a third of its time on them. Safe where the array outlives every
    use of the result: the caller holds it for the call, and nothing taken from it is kept or returned.
    Plain Python (tests, the interpreted kernel): the array itself."""
    return array


@intrinsic
def _without_meminfo(typingctx, array):
    def codegen(context, builder, signature, args):
        view = context.make_array(signature.args[0])(context, builder, value=args[0])
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        view.parent = cgutils.get_null_value(view.parent.type)
        return view._getvalue()

    return array(array), codegen


@overload(unmanaged)
def _unmanaged_compiled(array):
    if isinstance(array, types.Array):
        return lambda array: _without_meminfo(array)


@register_jitable
def sample(gyr, acc, dt, mag, k):
    """Row k of ``run``'s arrays as a kernel's inputs after (state, params); ``mag`` (0, 3) for none."""
    if mag.shape[0] == 0:
        return gyr[k, 0], gyr[k, 1], gyr[k, 2], acc[k, 0], acc[k, 1], acc[k, 2], dt[k], math.nan, math.nan, math.nan
    return gyr[k, 0], gyr[k, 1], gyr[k, 2], acc[k, 0], acc[k, 1], acc[k, 2], dt[k], mag[k, 0], mag[k, 1], mag[k, 2]


@register_jitable
def sample_fix(gps, k):
    """Row k of ``run``'s GPS rows as a GPS-aided kernel's last four inputs; ``gps`` (0, 4) for none."""
    if gps.shape[0] == 0:
        return math.nan, math.nan, math.nan, math.nan
    return gps[k, 0], gps[k, 1], gps[k, 2], gps[k, 3]


@register_jitable
def record(state, k, status, status_out, q_out, diag_out):
    """Row k of ``run``'s outputs from the kernel's status and state: what ``step`` returns."""
    status_out[k] = status
    for i in range(4):
        q_out[k, i] = state[i]
    for i in range(diag_out.shape[1]):
        diag_out[k, i] = state[STATE_DIAG + i]


_READY = set()  # the dispatchers compiled for their one signature
_COMPILING = threading.Lock()
# Sources every kernel and run loop compiles in besides its own file (guard, sample, record; tilt; compass)
_SHARED_SOURCES = (Path(__file__), Path(tilt.__file__), Path(compass.__file__))


def drop_stale_cache(dispatcher, shared_sources=_SHARED_SOURCES) -> None:
    """numba checks a cached function against its own file only: its index (``<module>.<name>-<line>.*.nbi``)
    is deleted when older than a shared source, so numba compiles an edit there instead of loading the
    function compiled before it (a missing index is just compiled anew)."""
    newest = max(path.stat().st_mtime for path in shared_sources)
    function = dispatcher.py_func
    pattern = f"{Path(function.__code__.co_filename).stem}.{function.__qualname__}-*.nbi"
    for index in Path(dispatcher.stats.cache_path).glob(pattern):
        if index.stat().st_mtime < newest:
            index.unlink(missing_ok=True)


def _compiled(dispatcher, signature):
    """The dispatcher compiled (or loaded from numba's cache) for exactly this signature, on first use;
    one thread at a time (two files loading at once: a second thread calling it between another's compile
    and ``_READY`` would meet "compilation disabled")."""
    if dispatcher not in _READY:
        with _COMPILING:
            if dispatcher not in _READY:
                drop_stale_cache(dispatcher)
                dispatcher.compile(signature)
                dispatcher.disable_compile()  # other argument types are converted to these, never compiled anew
                _READY.add(dispatcher)
    return dispatcher


def _loaded(dispatcher, signature) -> bool:
    """Whether the dispatcher is ready for this signature without compiling it here: compiled or loaded
    before, or loaded now from numba's cache (some milliseconds). Never compiles (seconds, holding the GIL):
    a live session runs the kernel's source interpreted meanwhile (``CompiledEstimator.ready_or_interpreted``).
    The cache is read as ``Dispatcher.compile`` reads it first (numba 0.68's private ``_cache``, there is no
    public "load only"); a signature the cache lacks (or one made on another CPU) is False. Under ``_compiled``'s
    lock: disabling compilation while another thread's ``_compiled`` is about to compile would fail it."""
    if dispatcher in _READY:
        return True
    with _COMPILING:
        if dispatcher in _READY:
            return True
        drop_stale_cache(dispatcher)
        cres = dispatcher._cache.load_overload(signature, dispatcher.targetctx)
        if cres is None:
            return False
        dispatcher.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
        dispatcher.add_overload(cres)
        dispatcher.disable_compile()  # as ``_compiled``
        _READY.add(dispatcher)
        return True


_new_tuple = tuple.__new__
_NO_FIELD = (math.nan, math.nan, math.nan)
_NO_FIX = (math.nan, math.nan, math.nan, math.nan)


class CompiledEstimator(Estimator):
    """An estimator whose per-sample arithmetic is a compiled ``kernel`` (module docstring).

    Subclasses set ``kernel`` (``staticmethod`` of an ``@njit(cache=True)`` function with
    ``KERNEL_SIGNATURE``), ``run_kernel`` (likewise, ``RUN_SIGNATURE``: ``state, params = unmanaged(state),
    unmanaged(params)``, then the loop ``for k: record(..., kernel(state, params, *sample(..., k)), ...)``, written out in each kernel's module because a
    kernel passed as an argument cannot be cached, and a kernel passed from Python costs ~0.5 ms a
    call to convert) and ``uses_magnetometer``, and implement ``_parameters()`` (their own
    parameters, after the guard's) and ``_initial_state()`` (their diagnostics after status, then their
    own state, as after ``reset()``). ``dtype`` None runs the compiled kernel on float64; a numpy type
    runs the same source interpreted on numbers of that type (ahf's float32 firmware model): ``step``
    then returns numbers of that type, ``run`` widens them to float64 (exactly).
    """

    kernel: ClassVar
    run_kernel: ClassVar
    gps_aided: ClassVar[bool] = False  # the kernel takes the GPS fix too (GPS_KERNEL_SIGNATURE)

    def __init__(self, settings=None, dtype=None):
        self._dtype = np.dtype(np.float64 if dtype is None else dtype)
        self._cast = None if dtype is None else self._dtype.type
        kernel = type(self).kernel
        self._kernel = _compiled(kernel, self._signature()) if dtype is None else kernel.py_func
        self._diag_end = STATE_DIAG + len(self.Diagnostics._fields) - 1
        super().__init__(settings)

    @classmethod
    def _signature(cls):
        return GPS_KERNEL_SIGNATURE if cls.gps_aided else KERNEL_SIGNATURE

    @classmethod
    def ready_or_interpreted(cls, settings=None) -> CompiledEstimator:
        """Compiled if its kernel is compiled or in numba's cache, else its source interpreted on float64 (the
        same numbers within 1e-12, tests/estimation/test_kernels.py) until ``take_compiled``."""
        return cls(settings) if _loaded(cls.kernel, cls._signature()) else cls(settings, dtype=np.float64)

    @classmethod
    def runs_compiled(cls) -> bool:
        run_signature = GPS_RUN_SIGNATURE if cls.gps_aided else RUN_SIGNATURE
        return _loaded(cls.kernel, cls._signature()) and _loaded(cls.run_kernel, run_signature)

    @property
    def interpreted(self) -> bool:
        return self._cast is not None

    def take_compiled(self) -> bool:
        """An estimator made by ``ready_or_interpreted`` goes on with the compiled kernel, its state kept, once
        the kernel is in numba's cache (another process compiled it: ``estimation.warm_up``); whether it
        runs compiled now."""
        if self._cast is None:
            return True
        if self._dtype != np.float64 or not _loaded(type(self).kernel, self._signature()):
            return False  # a float32 model stays one
        self._kernel, self._cast = type(self).kernel, None
        self._params = np.asarray(self._params, dtype=np.float64)  # the interpreted one's is a list
        return True

    def _parameters(self) -> list[float]:
        raise NotImplementedError

    def _initial_state(self) -> list[float]:
        raise NotImplementedError

    def reset(self, q0=None) -> None:
        s = self.settings
        guards = [self._acc_min2, s.acc_deviation_max_g, s.acc_window_s, s.max_gap_s, float(self.uses_magnetometer)]
        self._params = np.array(guards + self._parameters(), dtype=self._dtype)
        if self._cast is not None:  # interpreted: a list of numpy scalars reads 3x faster than an array
            self._params = list(self._params)
        q = (1.0, 0.0, 0.0, 0.0) if q0 is None else quaternion.normalise(q0).tolist()
        self._state = np.array([*q, float(q0 is None), 0.0, 0.0, *[0.0] * (STATE_DIAG - STATE_MAG), *self._initial_state()], dtype=self._dtype)

    @property
    def _q(self):
        return tuple(self._values()[:4])

    @property
    def _acc_dev(self):
        return self._state[STATE_ACC_DEV]

    def _values(self):
        # tolist(): Python floats for step's output; the interpreted model keeps its numpy type
        return self._state.tolist() if self._cast is None else list(self._state)

    def step(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        gx, gy, gz = gyr_rad_s
        ax, ay, az = acc_g
        mx, my, mz = _NO_FIELD if mag is None else mag
        fix = (_NO_FIX if gps is None else gps) if self.gps_aided else ()
        if self._cast is None:
            status = self._kernel(self._state, self._params, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz, *fix)
        else:
            c = self._cast
            gx, gy, gz, ax, ay, az, dt_s = c(gx), c(gy), c(gz), c(ax), c(ay), c(az), c(dt_s)
            with np.errstate(all="ignore"):  # an inf - inf is NaN without a word, as in the compiled kernel and the C core
                status = self._kernel(self._state, self._params, gx, gy, gz, ax, ay, az, dt_s, mx, my, mz, *fix)
        v = self._values()
        return (v[0], v[1], v[2], v[3]), _new_tuple(self.Diagnostics, (status, *v[STATE_DIAG : self._diag_end]))

    def run(self, gyr_rad_s, acc_g, dt_s, mag=None, gps=None):
        gyr, acc, dt = batch_inputs(gyr_rad_s, acc_g, dt_s)
        n = len(dt)
        mags = np.empty((0, 3)) if mag is None else _rows(mag, n, 3, "mag")
        fixes = np.empty((0, 4)) if gps is None else _rows(gps, n, 4, "gps")  # checked even where unused
        q, status, table = np.empty((n, 4)), np.empty(n, dtype=np.int64), np.empty((n, self._diag_end - STATE_DIAG))
        aiding = (mags, fixes) if self.gps_aided else (mags,)
        if self._cast is None:
            signature = GPS_RUN_SIGNATURE if self.gps_aided else RUN_SIGNATURE
            _compiled(type(self).run_kernel, signature)(self._state, self._params, gyr, acc, dt, *aiding, q, status, table)
        else:  # the same loop, interpreted (run_kernel.py_func would call the compiled kernel)
            gyr, acc, dt, mags = (a.astype(self._dtype) for a in (gyr, acc, dt, mags))
            for k in range(n):
                fix = sample_fix(fixes, k) if self.gps_aided else ()
                record(self._state, k, self._kernel(self._state, self._params, *sample(gyr, acc, dt, mags, k), *fix), status, q, table)
        return q, {"status": status} | {name: table[:, i] for i, name in enumerate(self.Diagnostics._fields[1:])}


def _rows(values, n: int | None, width: int, name: str) -> np.ndarray:
    """(n, width) contiguous writable float64; any n when None."""
    rows = np.require(np.asarray(values, dtype=float).reshape(-1, width), requirements="CW")
    if n is not None and len(rows) != n:
        raise ValueError(f"{name} has {len(rows)} rows of {width}, expected {n}")
    return rows

"""Sensor calibration: gyro bias from a static interval, rest detection, stored accelerometer calibration.

The paper calibrated both sensors' zero offsets before its tests (seed 000 §4.1). The gyro bias is the
mean rate over samples known to be at rest; ``detect_rest`` finds such samples. The accelerometer's
bias and scale come from a stored calibration (e.g. a six-position calibration done once), applied as
``(acc - bias) * scale`` per axis.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def detect_rest(gyr_rad_s, acc_g, window: int = 50, gyro_max_rad_s: float = 0.03, acc_std_max_g: float = 0.01):
    """Boolean mask (N,): True where the sample lies in a window of ``window`` samples that is still.

    Still means every gyro norm in the window is below ``gyro_max_rad_s`` (a raw MPU-6050 at rest reads
    its bias, up to about ±20 °/s uncalibrated, so raise it for an uncalibrated gyro) and the accelerometer
    norm's standard deviation over the window is below ``acc_std_max_g``. Shorter series than ``window``
    are never at rest.
    """
    gyr = np.asarray(gyr_rad_s, dtype=float).reshape(-1, 3)
    acc = np.asarray(acc_g, dtype=float).reshape(-1, 3)
    n = len(gyr)
    rest = np.zeros(n, dtype=bool)
    if n < window:
        return rest
    gyro_windows = sliding_window_view(np.linalg.norm(gyr, axis=1), window)
    acc_windows = sliding_window_view(np.linalg.norm(acc, axis=1), window)
    # NaN makes max/std NaN and the comparison False: a window with a bad sample is not at rest.
    still = (gyro_windows.max(axis=1) < gyro_max_rad_s) & (acc_windows.std(axis=1) < acc_std_max_g)
    for start in np.flatnonzero(still):
        rest[start : start + window] = True
    return rest


def gyro_bias_rad_s(gyr_rad_s, rest=None) -> np.ndarray:
    """Mean gyro rate (3,) over the rest samples (all samples if ``rest`` is None); ValueError if none."""
    gyr = np.asarray(gyr_rad_s, dtype=float).reshape(-1, 3)
    if rest is not None:
        gyr = gyr[np.asarray(rest, dtype=bool)]
    gyr = gyr[np.all(np.isfinite(gyr), axis=1)]
    if len(gyr) == 0:
        raise ValueError("no finite samples at rest to estimate the gyro bias from")
    return gyr.mean(axis=0)


@dataclasses.dataclass(frozen=True)
class AccelCalibration:
    """Stored accelerometer calibration, body axes: ``calibrated = (raw - bias_g) * scale``."""

    bias_g: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)  # dimensionless, per axis

    def apply(self, acc_g) -> np.ndarray:
        return (np.asarray(acc_g, dtype=float) - np.asarray(self.bias_g)) * np.asarray(self.scale)


class RestBiasCalibrator:
    """Gyro bias measured while the craft is still, sample by sample (the live counterpart of
    ``detect_rest`` + ``gyro_bias_rad_s``)::

        cal = RestBiasCalibrator()
        bias = cal.step(gyr_rad_s, acc_g, dt_s, armed, mag_ut, gps)   # None until measured, then 3 floats, rad/s

    Still means, over a window of ``duration_s`` of consecutive samples: every gyro axis's standard
    deviation below ``gyro_std_max_rad_s`` and every accelerometer axis's below ``acc_std_max_g`` (noise
    only: no motion, no vibration), the mean accelerometer norm within ``acc_dev_max_g`` of 1 g, every
    magnetometer axis's standard deviation below ``mag_std_max_ut`` (readings that arrived, if any) and
    every GPS fix's speed below ``gps_speed_max_m_s``. Then the window's mean rate is the bias and stays
    fixed; a window that is not still starts a new one. The gyro's magnitude says nothing (a board that
    skipped its boot calibration streams a bias up to ±20 °/s), so a steady turn, whose rate has no
    variance and whose specific force stays near 1 g at a small bank, is told from a bias by the
    magnetometer turning with it or by the GPS speed; with neither, a steady turn at a small bank cannot
    be told from a bias by these sensors. Refused, the window restarted: below ``min_rate_hz`` (a window of
    2 s at 4 Hz is 8 samples, too few to tell a turn from the noise), a non-finite sample, and while a
    MAVLink vehicle is ``armed`` (it may be flying however still it looks). ``restart()`` measures again
    (the user's command, once the craft is put down).
    """

    def __init__(self, duration_s: float = 2.0, gyro_std_max_rad_s: float = math.radians(0.5), acc_std_max_g: float = 0.01,
                 acc_dev_max_g: float = 0.05, mag_std_max_ut: float = 1.5, gps_speed_max_m_s: float = 1.0, min_rate_hz: float = 20.0):
        bounds = (duration_s, gyro_std_max_rad_s, acc_std_max_g, acc_dev_max_g, mag_std_max_ut, gps_speed_max_m_s, min_rate_hz)
        if not all(v > 0 for v in bounds):
            raise ValueError("duration_s, the deviation, field and speed bounds and min_rate_hz must be positive")
        self.duration_s = duration_s
        self.gyro_std_max_rad_s = gyro_std_max_rad_s
        self.acc_std_max_g = acc_std_max_g
        self.acc_dev_max_g = acc_dev_max_g
        self.mag_std_max_ut = mag_std_max_ut
        self.gps_speed_max_m_s = gps_speed_max_m_s
        self.max_dt_s = 1.0 / min_rate_hz
        self.restart()

    def restart(self) -> None:
        self.bias_rad_s: tuple[float, float, float] | None = None
        self._new_window()

    def _new_window(self) -> None:
        self._imu = _Moments(6)  # gyro x y z, acc x y z
        self._mag = _Moments(3)
        self._still_s = 0.0

    def measure(self, gyr_rad_s, acc_g, dt_s, armed=None, mag_ut=None, gps=None) -> int | None:
        """``step`` over (N, 3), (N, 3), (N,) float64 arrays, with the optional (N,) ``armed`` and the (N, 3)
        ``mag_ut`` and (N, 4) ``gps`` of ``Estimator.run`` (NaN rows: none), from a fresh start, stopping
        where the bias is measured: returns that sample's index (``bias_rad_s`` set, bit for bit as ``step``
        sets it), or None. Window by window: the sums are running sums (``np.cumsum`` adds in order, as
        ``step`` does) from the window's first sample."""
        if self._imu.n or self.bias_rad_s is not None:
            raise ValueError("measure() starts from a fresh calibrator")
        imu = np.column_stack([gyr_rad_s, acc_g]).astype(float, copy=False)
        dt = np.asarray(dt_s, dtype=float)
        n = len(dt)
        with np.errstate(invalid="ignore"):
            refused = ~(np.isfinite(imu).all(axis=1) & (dt > 0.0) & (dt <= self.max_dt_s))
        if armed is not None:
            refused |= np.asarray(armed, dtype=bool)
        if gps is not None:
            fixes = np.asarray(gps, dtype=float).reshape(-1, 4)
            for k in np.flatnonzero(~np.isnan(fixes).all(axis=1)).tolist():
                refused[k] |= not math.hypot(*fixes[k, :3].tolist()) <= self.gps_speed_max_m_s
        mags = None if mag_ut is None else np.asarray(mag_ut, dtype=float).reshape(-1, 3)
        refusals = np.flatnonzero(refused)
        start, span = 0, 256
        while start < n:
            if refused[start]:
                start += 1
                continue
            j = np.searchsorted(refusals, start)
            stop = int(refusals[j]) if j < len(refusals) else n  # the window cannot reach past a refusal
            still_s = np.cumsum(dt[start : min(stop, start + span)])
            done = np.flatnonzero(still_s >= self.duration_s)
            if not len(done):
                if start + span < stop:
                    span *= 2  # the window is longer than the samples looked at: look further
                else:
                    start = stop
                continue
            end = start + int(done[0]) + 1
            self._imu = _Moments.of(imu[start:end])
            if mags is not None:
                block = mags[start:end]
                self._mag = _Moments.of(block[np.isfinite(block).all(axis=1)])
            self._still_s = float(still_s[done[0]])
            if self._judge():
                return end - 1
            start = end
        self._new_window()
        return None

    def step(self, gyr_rad_s, acc_g, dt_s, armed: bool = False, mag_ut=None, gps=None):
        """One sample; ``mag_ut`` the magnetometer reading (µT) and ``gps`` the fix ((vel_n, vel_e, vel_d m/s,
        ...)) that arrived since the previous sample, None when none did."""
        if self.bias_rad_s is not None:
            return self.bias_rad_s
        values = (*gyr_rad_s, *acc_g)
        # NaN fails every comparison: a bad sample or interval refuses like a slow rate or an armed vehicle.
        moving = gps is not None and not math.hypot(gps[0], gps[1], gps[2]) <= self.gps_speed_max_m_s
        if armed or moving or not (0.0 < dt_s <= self.max_dt_s) or not all(abs(v) < math.inf for v in values):
            self._new_window()
            return None
        self._imu.add(values)
        if mag_ut is not None and all(abs(v) < math.inf for v in mag_ut):
            self._mag.add(mag_ut)
        self._still_s += dt_s
        if self._still_s >= self.duration_s:
            self._judge()
        return self.bias_rad_s

    def _judge(self) -> bool:
        """At the end of a window: the bias if it was still (True), else a new window."""
        mean, var = self._imu.mean_var()
        still = all(v <= self.gyro_std_max_rad_s**2 for v in var[:3]) and all(v <= self.acc_std_max_g**2 for v in var[3:])
        still = still and abs(math.hypot(*mean[3:]) - 1.0) <= self.acc_dev_max_g
        if self._mag.n >= 2:
            still = still and all(v <= self.mag_std_max_ut**2 for v in self._mag.mean_var()[1])
        if still:
            self.bias_rad_s = (mean[0], mean[1], mean[2])
        else:
            self._new_window()
        return still


class _Moments:
    """Running sums of values and their squares: means and (population) variances per channel."""

    def __init__(self, width: int):
        self.n = 0
        self._sums = [0.0] * width
        self._squares = [0.0] * width

    def add(self, values) -> None:
        self.n += 1
        for i, v in enumerate(values):
            self._sums[i] += v
            self._squares[i] += v * v

    @classmethod
    def of(cls, rows: np.ndarray) -> "_Moments":
        """The moments of (n, width) rows, summed in order as ``add`` sums them."""
        moments = cls(rows.shape[1])
        moments.n = len(rows)
        if len(rows):
            moments._sums = np.cumsum(rows, axis=0)[-1].tolist()
            moments._squares = np.cumsum(rows * rows, axis=0)[-1].tolist()
        return moments

    def mean_var(self):
        mean = [s / self.n for s in self._sums]
        return mean, [max(0.0, q / self.n - m * m) for q, m in zip(self._squares, mean)]

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
        bias = cal.step(gyr_rad_s, acc_g, dt_s, armed=False)   # None until measured, then (3 floats, rad/s)

    Still means, over a window of ``duration_s`` of consecutive samples: every gyro axis's standard
    deviation below ``gyro_std_max_rad_s`` and every accelerometer axis's below ``acc_std_max_g`` (noise
    only: no motion, no vibration), the mean accelerometer norm within ``acc_dev_max_g`` of 1 g, and the
    mean rate within ``bias_max_rad_s`` (the gyro the host gets was calibrated at boot, by the board or
    the autopilot, so a larger steady rate is a turn: a loiter has a steady rate with no variance at
    all). Then the window's mean rate is the bias and stays fixed; a window that is not still starts a
    new one. Refused, the window restarted: below ``min_rate_hz`` (a window of 2 s at 4 Hz is 8 samples,
    too few to tell a turn from the noise), a non-finite sample, and while a MAVLink vehicle is
    ``armed`` (it may be flying however still it looks). A steady turn slower than ``bias_max_rad_s``
    cannot be told from a bias by these sensors. ``restart()`` measures again (the user's command, once
    the craft is put down).
    """

    def __init__(self, duration_s: float = 2.0, gyro_std_max_rad_s: float = math.radians(0.5), acc_std_max_g: float = 0.01,
                 acc_dev_max_g: float = 0.05, bias_max_rad_s: float = math.radians(3.0), min_rate_hz: float = 20.0):
        if not all(v > 0 for v in (duration_s, gyro_std_max_rad_s, acc_std_max_g, acc_dev_max_g, bias_max_rad_s, min_rate_hz)):
            raise ValueError("duration_s, the deviation and bias bounds and min_rate_hz must be positive")
        self.duration_s = duration_s
        self.gyro_std_max_rad_s = gyro_std_max_rad_s
        self.acc_std_max_g = acc_std_max_g
        self.acc_dev_max_g = acc_dev_max_g
        self.bias_max_rad_s = bias_max_rad_s
        self.max_dt_s = 1.0 / min_rate_hz
        self.restart()

    def restart(self) -> None:
        self.bias_rad_s: tuple[float, float, float] | None = None
        self._new_window()

    def _new_window(self) -> None:
        self._sums = [0.0] * 12  # gyro x y z, acc x y z, then their squares
        self._n = 0
        self._still_s = 0.0

    def measure(self, gyr_rad_s, acc_g, dt_s, armed=None) -> int | None:
        """``step`` over (N, 3), (N, 3), (N,) arrays (and an optional (N,) ``armed``) from a fresh start,
        stopping where the bias is measured: returns that sample's index (``bias_rad_s`` set), or None."""
        if self._n or self.bias_rad_s is not None:
            raise ValueError("measure() starts from a fresh calibrator")
        flags = [False] * len(dt_s) if armed is None else np.asarray(armed, dtype=bool).tolist()
        for k, (g, a, d, on) in enumerate(zip(np.asarray(gyr_rad_s).tolist(), np.asarray(acc_g).tolist(), np.asarray(dt_s).tolist(), flags)):
            if self.step(g, a, d, on) is not None:
                return k
        return None

    def step(self, gyr_rad_s, acc_g, dt_s, armed: bool = False):
        if self.bias_rad_s is not None:
            return self.bias_rad_s
        values = (*gyr_rad_s, *acc_g)
        # NaN fails every comparison: a bad sample or interval refuses like a slow rate or an armed vehicle.
        if armed or not (0.0 < dt_s <= self.max_dt_s) or not all(abs(v) < math.inf for v in values):
            self._new_window()
            return None
        sums = self._sums
        for i, v in enumerate(values):
            sums[i] += v
            sums[i + 6] += v * v
        self._n += 1
        self._still_s += dt_s
        if self._still_s >= self.duration_s:
            n = self._n
            mean = [v / n for v in sums[:6]]
            var = [max(0.0, sums[i + 6] / n - mean[i] * mean[i]) for i in range(6)]
            gyro_still = all(v <= self.gyro_std_max_rad_s**2 for v in var[:3])
            acc_still = all(v <= self.acc_std_max_g**2 for v in var[3:])
            level = abs(math.sqrt(mean[3] ** 2 + mean[4] ** 2 + mean[5] ** 2) - 1.0) <= self.acc_dev_max_g
            slow = math.sqrt(mean[0] ** 2 + mean[1] ** 2 + mean[2] ** 2) <= self.bias_max_rad_s
            if gyro_still and acc_still and level and slow:
                self.bias_rad_s = (mean[0], mean[1], mean[2])
            else:
                self._new_window()
        return self.bias_rad_s

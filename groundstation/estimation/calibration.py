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
        bias = cal.step(gyr_rad_s, acc_g, dt_s)   # None until measured, then the bias (3 floats, rad/s)

    Still: every gyro axis within ``gyro_dev_max_rad_s`` of the running mean (the mean itself is the
    bias, up to ±20 °/s on an uncalibrated MPU-6050, so magnitude says nothing) and the accelerometer
    within ``acc_dev_max_g`` of 1 g on every sample. After ``duration_s`` of still samples the mean is the
    bias and stays fixed; any motion first restarts the count. ``restart()`` measures again (the user's
    command, once the craft is put down).
    """

    def __init__(self, duration_s: float = 2.0, gyro_dev_max_rad_s: float = 0.02, acc_dev_max_g: float = 0.05):
        if not duration_s > 0 or not gyro_dev_max_rad_s > 0 or not acc_dev_max_g > 0:
            raise ValueError("duration_s, gyro_dev_max_rad_s and acc_dev_max_g must be positive")
        self.duration_s = duration_s
        self.gyro_dev_max_rad_s = gyro_dev_max_rad_s
        self.acc_dev_max_g = acc_dev_max_g
        self.restart()

    def restart(self) -> None:
        self.bias_rad_s: tuple[float, float, float] | None = None
        self._sum = [0.0, 0.0, 0.0]
        self._n = 0
        self._still_s = 0.0

    def measure(self, gyr_rad_s: np.ndarray, acc_g: np.ndarray, dt_s: np.ndarray) -> int | None:
        """``step`` over (N, 3), (N, 3), (N,) float64 arrays from a fresh start, stopping where the bias is
        measured: returns that sample's index (``bias_rad_s`` is then set, bit for bit as ``step`` sets
        it), or None. The sums are running sums (``np.cumsum`` adds in order, as ``step`` does) from the
        last restart of the count; where a sample restarts it, the next one starts over.
        """
        if self._n or self.bias_rad_s is not None:
            raise ValueError("measure() starts from a fresh calibrator")
        n = len(dt_s)
        ax, ay, az = acc_g[:, 0], acc_g[:, 1], acc_g[:, 2]
        with np.errstate(invalid="ignore", over="ignore"):
            norm = np.sqrt(ax * ax + ay * ay + az * az)  # correctly rounded, as math.sqrt in step
            acc_still = (np.abs(norm - 1.0) <= self.acc_dev_max_g) & (dt_s > 0)
        candidates = np.flatnonzero(acc_still)
        start, window = 0, 64
        while True:
            i = np.searchsorted(candidates, start)
            if i == len(candidates):
                return None
            start = int(candidates[i])
            end = min(n, start + window)
            block = acc_still[start:end]
            end = start + (int(np.argmin(block)) if not block.all() else len(block))  # the acc-still run
            sums = np.cumsum(gyr_rad_s[start:end], axis=0)
            counts = np.arange(1, end - start)[:, None]
            with np.errstate(invalid="ignore"):
                deviation = np.abs(gyr_rad_s[start + 1 : end] - sums[:-1] / counts)
                still = np.concatenate(([True], (deviation <= self.gyro_dev_max_rad_s).all(axis=1)))
            stop = int(np.argmin(still)) if not still.all() else end - start  # the first sample that moved
            still_s = np.cumsum(dt_s[start : start + stop])
            done = np.flatnonzero(still_s >= self.duration_s)
            if len(done):
                k = int(done[0])
                self._n, self._still_s = k + 1, float(still_s[k])
                self._sum = sums[k].tolist()
                self.bias_rad_s = tuple((sums[k] / (k + 1)).tolist())
                return start + k
            if stop == end - start and end < n and acc_still[end - 1] and end - start == window:
                window *= 2  # still going at the window's end: look further at once
                continue
            start, window = start + stop + (stop < end - start), 64

    def step(self, gyr_rad_s, acc_g, dt_s):
        if self.bias_rad_s is not None:
            return self.bias_rad_s
        gx, gy, gz = gyr_rad_s
        ax, ay, az = acc_g
        n2 = ax * ax + ay * ay + az * az
        # NaN fails every comparison: a bad sample is not still.
        still = abs(math.sqrt(n2) - 1.0) <= self.acc_dev_max_g and dt_s > 0
        if still and self._n:
            m = self.gyro_dev_max_rad_s
            sx, sy, sz = (s / self._n for s in self._sum)
            still = abs(gx - sx) <= m and abs(gy - sy) <= m and abs(gz - sz) <= m
        if not still:
            self._sum, self._n, self._still_s = [0.0, 0.0, 0.0], 0, 0.0
            return None
        self._sum = [self._sum[0] + gx, self._sum[1] + gy, self._sum[2] + gz]
        self._n += 1
        self._still_s += dt_s
        if self._still_s >= self.duration_s:
            self.bias_rad_s = tuple(s / self._n for s in self._sum)
        return self.bias_rad_s

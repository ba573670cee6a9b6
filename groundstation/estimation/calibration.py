"""Sensor calibration: gyro bias from a static interval, rest detection, stored accelerometer calibration.

The paper calibrated both sensors' zero offsets before its tests (seed 000 §4.1). The gyro bias is the
mean rate over samples known to be at rest; ``detect_rest`` finds such samples. The accelerometer's
bias and scale come from a stored calibration (e.g. a six-position calibration done once), applied as
``(acc - bias) * scale`` per axis.
"""

from __future__ import annotations

import dataclasses

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

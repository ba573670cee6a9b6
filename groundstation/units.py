"""MPU-6050 raw counts to physical units and back, for each configurable full scale.

The sensor outputs int16 counts; the sensitivity depends on the full scale set in the device
(ACCEL_CONFIG / GYRO_CONFIG). The CONFIG frame of the protocol carries that full scale as
``accel_fs_g`` (2, 4, 8 or 16) and ``gyro_fs_dps`` (250, 500, 1000 or 2000). Sensitivities are the
datasheet's (MPU-6000/6050 Product Specification rev 3.4, tables 6.1 and 6.2): the gyro's are the
rounded 131, 65.5, 32.8 and 16.4 LSB/(°/s), not 32768/full-scale.

Conversions accept scalars or numpy arrays. The inverse conversions round to the nearest count and
saturate at the int16 limits, as the sensor does.
"""

from __future__ import annotations

import math

import numpy as np

STANDARD_GRAVITY_M_S2 = 9.80665

ACCEL_LSB_PER_G: dict[int, float] = {2: 16384.0, 4: 8192.0, 8: 4096.0, 16: 2048.0}
GYRO_LSB_PER_DPS: dict[int, float] = {250: 131.0, 500: 65.5, 1000: 32.8, 2000: 16.4}

INT16_MIN, INT16_MAX = -32768, 32767


def _accel_lsb_per_g(accel_fs_g: int) -> float:
    try:
        return ACCEL_LSB_PER_G[accel_fs_g]
    except KeyError:
        raise ValueError(f"accelerometer full scale must be one of {sorted(ACCEL_LSB_PER_G)} g, not {accel_fs_g!r}") from None


def _gyro_lsb_per_dps(gyro_fs_dps: int) -> float:
    try:
        return GYRO_LSB_PER_DPS[gyro_fs_dps]
    except KeyError:
        raise ValueError(f"gyro full scale must be one of {sorted(GYRO_LSB_PER_DPS)} °/s, not {gyro_fs_dps!r}") from None


def _to_int16(value):
    return np.clip(np.rint(value), INT16_MIN, INT16_MAX).astype(np.int16)


def accel_counts_to_g(counts, accel_fs_g: int):
    return np.asarray(counts, dtype=float) / _accel_lsb_per_g(accel_fs_g)


def accel_counts_to_m_s2(counts, accel_fs_g: int):
    return accel_counts_to_g(counts, accel_fs_g) * STANDARD_GRAVITY_M_S2


def accel_g_to_counts(acc_g, accel_fs_g: int) -> np.ndarray:
    return _to_int16(np.asarray(acc_g, dtype=float) * _accel_lsb_per_g(accel_fs_g))


def accel_m_s2_to_counts(acc_m_s2, accel_fs_g: int) -> np.ndarray:
    return accel_g_to_counts(np.asarray(acc_m_s2, dtype=float) / STANDARD_GRAVITY_M_S2, accel_fs_g)


def gyro_counts_to_dps(counts, gyro_fs_dps: int):
    return np.asarray(counts, dtype=float) / _gyro_lsb_per_dps(gyro_fs_dps)


def gyro_counts_to_rad_s(counts, gyro_fs_dps: int):
    return gyro_counts_to_dps(counts, gyro_fs_dps) * (math.pi / 180.0)


def gyro_dps_to_counts(gyr_dps, gyro_fs_dps: int) -> np.ndarray:
    return _to_int16(np.asarray(gyr_dps, dtype=float) * _gyro_lsb_per_dps(gyro_fs_dps))


def gyro_rad_s_to_counts(gyr_rad_s, gyro_fs_dps: int) -> np.ndarray:
    return gyro_dps_to_counts(np.asarray(gyr_rad_s, dtype=float) * (180.0 / math.pi), gyro_fs_dps)


def gyro_limit_rad_s(gyro_fs_dps: int) -> float:
    """The largest rate the gyro can report at this full scale (int16 max), in rad/s."""
    return INT16_MAX / _gyro_lsb_per_dps(gyro_fs_dps) * (math.pi / 180.0)


# Temperature sensor (register map rev 4.2, TEMP_OUT): °C = counts / 340 + 36.53.
def temperature_counts_to_c(counts):
    return np.asarray(counts, dtype=float) / 340.0 + 36.53


def temperature_c_to_counts(temp_c) -> np.ndarray:
    return _to_int16((np.asarray(temp_c, dtype=float) - 36.53) * 340.0)

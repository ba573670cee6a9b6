"""Unit conversion against the datasheet's sensitivities, and the 24 mountings as proper rotations."""

import itertools
import math

import numpy as np
import pytest

from groundstation import mounting, units


@pytest.mark.parametrize("fs_g, lsb", [(2, 16384), (4, 8192), (8, 4096), (16, 2048)])
def test_accel_one_g_is_the_datasheet_sensitivity(fs_g, lsb):
    assert units.accel_counts_to_g(lsb, fs_g) == 1.0
    assert units.accel_counts_to_m_s2(-lsb, fs_g) == -9.80665
    assert units.accel_g_to_counts(1.0, fs_g) == lsb
    # Saturation at the full scale, as the sensor does.
    assert units.accel_g_to_counts(3.0 * fs_g, fs_g) == 32767
    assert units.accel_g_to_counts(-3.0 * fs_g, fs_g) == -32768


@pytest.mark.parametrize("fs_dps, lsb", [(250, 131.0), (500, 65.5), (1000, 32.8), (2000, 16.4)])
def test_gyro_counts_round_trip(fs_dps, lsb):
    assert units.gyro_counts_to_dps(lsb * 10, fs_dps) == pytest.approx(10.0)
    counts = np.arange(-32768, 32768, 97, dtype=np.int16)
    back = units.gyro_rad_s_to_counts(units.gyro_counts_to_rad_s(counts, fs_dps), fs_dps)
    np.testing.assert_array_equal(back, counts)
    assert units.gyro_limit_rad_s(fs_dps) == pytest.approx(math.radians(32767 / lsb))


def test_accel_si_round_trip_and_bad_full_scale():
    counts = np.arange(-32768, 32768, 101, dtype=np.int16)
    np.testing.assert_array_equal(units.accel_m_s2_to_counts(units.accel_counts_to_m_s2(counts, 4), 4), counts)
    with pytest.raises(ValueError, match="full scale"):
        units.accel_counts_to_g(1, 3)
    with pytest.raises(ValueError, match="full scale"):
        units.gyro_counts_to_dps(1, 300)


def test_temperature_datasheet_formula():
    assert units.temperature_counts_to_c(0) == pytest.approx(36.53)
    assert units.temperature_c_to_counts(36.53 + 10.0) == 3400


def test_there_are_24_distinct_proper_rotations():
    assert len(mounting.MOUNTING_MATRICES) == 24
    for m in mounting.MOUNTING_MATRICES:
        np.testing.assert_allclose(m @ m.T, np.eye(3))
        assert np.linalg.det(m) == pytest.approx(1.0)
    for a, b in itertools.combinations(mounting.MOUNTING_MATRICES, 2):
        assert not np.allclose(a, b)
    for i in range(24):
        assert mounting.index_of(mounting.matrix(i)) == i
    np.testing.assert_array_equal(mounting.matrix(0), np.eye(3))


def test_default_mounting_is_sensor_x_forward_y_left_z_up():
    # Board flat and level: the MPU-6050's z axis (up) reads +1 g; in FRD body axes that is -1 g on z.
    np.testing.assert_allclose(mounting.sensor_to_body([0.0, 0.0, 1.0]), [0.0, 0.0, -1.0])
    # Sensor +y is the left wing.
    np.testing.assert_allclose(mounting.sensor_to_body([0.0, 1.0, 0.0]), [0.0, -1.0, 0.0])
    assert mounting.describe(mounting.DEFAULT_MOUNTING) == "sensor +x forward, -y right"


def test_named_axes_land_where_the_name_says():
    for i, (forward, right) in enumerate(mounting.MOUNTING_NAMES):
        f = np.zeros(3)
        f["xyz".index(forward[1])] = 1.0 if forward[0] == "+" else -1.0
        np.testing.assert_allclose(mounting.sensor_to_body(f, i), [1.0, 0.0, 0.0])
        v = np.random.default_rng(i).normal(size=(5, 3))
        np.testing.assert_allclose(mounting.body_to_sensor(mounting.sensor_to_body(v, i), i), v)


def test_bad_mounting_index():
    for bad in (-1, 24, 1.0, "1"):
        with pytest.raises(ValueError):
            mounting.matrix(bad)
    with pytest.raises(ValueError):
        mounting.index_of(np.diag([1.0, 1.0, -1.0]))  # a reflection is not a mounting

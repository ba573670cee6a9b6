"""Gyro bias from rest, rest detection and stored accelerometer calibration on synthetic data."""

import math
import random

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from groundstation.estimation.calibration import AccelCalibration, RestBiasCalibrator, detect_rest, gyro_bias_rad_s
from groundstation.readings import optional_rows


def synthetic(seed=21):
    """2 s rest, 2 s of motion, 2 s rest at 100 Hz, with a known gyro bias and MPU-6050-size noise."""
    rng = np.random.default_rng(seed)
    n = 600
    bias = np.array([0.02, -0.015, 0.008])
    gyr = bias + rng.normal(0.0, 0.001, (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 0.003, (n, 3))
    moving = slice(200, 400)
    gyr[moving] += np.column_stack([np.sin(np.arange(200) / 10.0)] * 3)
    acc[moving] += rng.normal(0.0, 0.2, (200, 3))
    return gyr, acc, bias


def test_rest_is_found_where_it_is_and_bias_recovered():
    gyr, acc, bias = synthetic()
    rest = detect_rest(gyr, acc, window=50, gyro_max_rad_s=0.05)
    assert rest[:150].all() and rest[450:].all()
    assert not rest[205:400].any()  # sin(0) = 0: the first motion samples are still still
    np.testing.assert_allclose(gyro_bias_rad_s(gyr, rest), bias, atol=3e-4)
    # Using every sample would be badly wrong: the motion does not average out.
    assert np.abs(gyro_bias_rad_s(gyr) - bias).max() > 0.005


def test_nan_and_short_inputs():
    gyr, acc, _ = synthetic()
    gyr[100] = np.nan
    rest = detect_rest(gyr, acc, window=50, gyro_max_rad_s=0.05)
    assert not rest[100]
    assert np.isfinite(gyro_bias_rad_s(gyr, rest)).all()
    assert not detect_rest(gyr[:10], acc[:10], window=50).any()
    with pytest.raises(ValueError, match="no finite samples"):
        gyro_bias_rad_s(gyr, np.zeros(len(gyr), dtype=bool))


def test_accel_calibration_undoes_bias_and_scale():
    true = np.array([[0.0, 0.0, -1.0], [0.5, -0.5, -0.7]])
    cal = AccelCalibration(bias_g=(0.02, -0.01, 0.03), scale=(1.0 / 1.02, 1.0 / 0.99, 1.0 / 1.01))
    raw = true * [1.02, 0.99, 1.01] + [0.02, -0.01, 0.03]
    np.testing.assert_allclose(cal.apply(raw), true, atol=1e-12)


def test_rest_bias_calibrator_measures_the_bias_after_the_still_time_and_keeps_it():
    gyr, acc, bias = synthetic()
    cal = RestBiasCalibrator(duration_s=1.0)
    out = [cal.step(g, a, 0.01) for g, a in zip(gyr.tolist(), acc.tolist())]
    assert all(b is None for b in out[:99]) and out[99] is not None  # 100 samples = 1 s of rest
    np.testing.assert_allclose(out[99], bias, atol=3e-4)  # independent truth: the synthetic bias
    assert all(b == out[99] for b in out[100:])  # fixed once measured, through the motion


def test_rest_bias_calibrator_restarts_on_motion_and_on_command():
    gyr, acc, bias = synthetic()
    cal = RestBiasCalibrator(duration_s=1.0)
    # Motion first (samples 200-399, then rest): measured only after 1 s of the final rest.
    out = [cal.step(g, a, 0.01) for g, a in zip(gyr[200:].tolist(), acc[200:].tolist())]
    first = next(i for i, b in enumerate(out) if b is not None)
    assert 200 + 99 <= first <= 200 + 110
    np.testing.assert_allclose(out[first], bias, atol=3e-4)
    cal.restart()
    assert cal.step(gyr[0], acc[0], 0.01) is None
    # NaN or a shaken accelerometer is not still
    cal.restart()
    assert cal.step([np.nan, 0.0, 0.0], acc[0], 0.01) is None and cal.step(gyr[0], [0.0, 0.0, -1.5], 0.01) is None
    with pytest.raises(ValueError):
        RestBiasCalibrator(duration_s=0.0)


KINDS = ["still", "moving", "tilted", "nan", "bad_dt", "drifting", "slow", "armed", "field_turning", "gps_moving"]


@settings(max_examples=60, derandomize=True)
@given(st.lists(st.tuples(st.integers(1, 150), st.sampled_from(KINDS)), min_size=1, max_size=12), st.integers(0, 2**32))
def test_measure_is_step_sample_for_sample(stretches, seed):
    """The batch path's calibrator: where it measures and the bias, bit for bit as step, over stretches
    at rest, moving, tilted (the accelerometer off 1 g), with NaN, with bad dt, slowly drifting, below
    20 Hz, armed, with a magnetometer turning and with a GPS saying it moves (magnetometer readings on
    every other sample and fixes on every tenth, NaN rows between)."""
    rng = random.Random(seed)  # the samples' noise: drawn here, not by hypothesis (too many draws)
    gyr, acc, dt, armed, mag, gps = [], [], [], [], [], []
    bias = [rng.uniform(-0.3, 0.3) for _ in range(3)]
    for length, kind in stretches:
        for k in range(length):
            noise = 0.03 if kind == "moving" else 0.004
            drift = 0.0001 * k if kind == "drifting" else 0.0
            gyr.append([b + drift + rng.gauss(0.0, noise) for b in bias])
            acc.append([rng.gauss(0.0, 0.01), rng.gauss(0.0, 0.01), -1.0 + (0.2 if kind == "tilted" else rng.gauss(0.0, 0.01))])
            dt.append(-0.01 if kind == "bad_dt" and k % 7 == 0 else 0.06 if kind == "slow" else 0.01)
            armed.append(kind == "armed")
            turn = 0.05 * k if kind == "field_turning" else 0.0
            mag.append([20.0 * math.cos(turn), 20.0 * math.sin(turn), 45.0 + rng.gauss(0.0, 0.3)] if len(mag) % 2 else [math.nan] * 3)
            gps.append([3.0 if kind == "gps_moving" else 0.1, 0.0, 0.0, math.nan] if len(gps) % 10 == 0 else [math.nan] * 4)
            if kind == "nan" and k % 5 == 0:
                gyr[-1][rng.randrange(3)] = math.nan
    gyr, acc, dt, mag, gps = np.array(gyr), np.array(acc), np.array(dt), np.array(mag), np.array(gps)
    one = RestBiasCalibrator(duration_s=0.5)
    rows = zip(gyr.tolist(), acc.tolist(), dt.tolist(), armed, optional_rows(mag, len(dt), 3, "mag"), optional_rows(gps, len(dt), 4, "gps"))
    expected = next((i for i, row in enumerate(rows) if one.step(*row)), None)
    batch = RestBiasCalibrator(duration_s=0.5)
    assert batch.measure(gyr, acc, dt, armed, mag, gps) == expected
    assert batch.bias_rad_s == one.bias_rad_s


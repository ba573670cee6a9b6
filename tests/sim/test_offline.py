"""The array simulator against its own truth: rates, units and axes of every sensor."""

import numpy as np

from groundstation import quaternion as quat
from groundstation.sim.offline import simulate


def test_sensors_report_at_their_rates_and_match_truth_within_their_noise():
    run = simulate("flight", 20.0, seed=5, mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=10)
    assert len(run) == 2000 and run.dt_s == 0.01
    assert np.isfinite(run.mag_ut[:, 0]).sum() == 1000
    assert np.isfinite(run.baro_alt_m).sum() == 500
    has_fix = np.isfinite(run.gps[:, 0])
    assert has_fix.sum() == 200 and np.array_equal(has_fix, np.isfinite(run.gps_pos_ned_m[:, 0]))
    truth = run.truth
    height_error = run.baro_alt_m + truth.pos_ned_m[:, 2]
    assert 0.1 < np.nanstd(height_error) < 0.3  # 2 Pa of pressure noise ≈ 0.17 m
    assert abs(np.nanmean(height_error)) < 0.1
    assert 0.7 < np.nanstd(run.gps_pos_ned_m - truth.pos_ned_m) < 1.3  # 1 m per axis
    yaw = quat.to_euler_zyx(truth.q_body_to_ned)[:, 0]
    heading_error = np.angle(np.exp(1j * (run.gps[has_fix, 3] - yaw[has_fix])))
    assert np.degrees(np.std(heading_error)) < 1.0


def test_imu_reads_the_body_rate_and_gravity_on_body_axes():
    run = simulate("static", 10.0, seed=1)
    assert np.allclose(run.acc_g.mean(axis=0), [0.0, 0.0, -1.0], atol=0.03)  # level, z down: -1 g
    assert np.allclose(run.gyr_rad_s.mean(axis=0), 0.0, atol=np.radians(0.5))  # calibrated at rest
    run = simulate("flight", 20.0, seed=2)
    assert np.corrcoef(run.gyr_rad_s[:, 0], run.truth.rate_body_rad_s[:, 0])[0, 1] > 0.99


def test_magnetometer_is_the_earth_field_rotated_onto_the_body_plus_hard_iron():
    run = simulate("flight", 10.0, seed=3, mag_rate_hz=100)
    expected = quat.rotate(quat.conjugate(run.truth.q_body_to_ned), np.array([20.0, 0.0, 45.0])) + run.hard_iron_ut
    assert np.allclose(run.mag_ut, expected, atol=1.5)  # 0.3 µT noise, 5σ

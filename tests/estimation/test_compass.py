"""Compass heading against simulator truth, with the craft tilted as it flies."""

import numpy as np

from groundstation import quaternion as quat
from groundstation.estimation.compass import heading_rad
from groundstation.sim.offline import simulate


def test_heading_from_the_true_tilt_is_the_true_yaw_within_the_magnetometer_noise():
    run = simulate("flight", 30.0, seed=4, mag_rate_hz=100)
    mag = run.mag_ut - run.hard_iron_ut  # hard iron known here; its estimation is the ellipsoid fit's job
    heading = heading_rad(run.truth.q_body_to_ned, mag)
    yaw = quat.to_euler_zyx(run.truth.q_body_to_ned)[:, 0]
    error_deg = np.degrees(np.angle(np.exp(1j * (heading - yaw))))
    assert np.abs(yaw).max() > np.radians(60)  # the flight turns, so heading is really exercised
    assert np.sqrt(np.mean(error_deg**2)) < 1.5  # 0.3 µT noise on a 20 µT horizontal field ≈ 0.9°
    assert np.all(np.isnan(heading_rad(run.truth.q_body_to_ned[:2], np.full((2, 3), np.nan))))

"""Compass heading against simulator truth, with the craft tilted as it flies."""

import numpy as np

from groundstation import quaternion as quat
from groundstation.estimation.compass import heading_rad, reading_heading_rad
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


def test_the_per_reading_heading_is_the_array_heading():
    """The float version (pipeline, per reading) against the array version over random attitudes and fields."""
    rng = np.random.default_rng(7)
    q = quat.normalise(rng.normal(size=(500, 4)))
    mag = rng.normal(size=(500, 3)) * 30.0
    expected = heading_rad(q, mag)
    got = np.array([reading_heading_rad(tuple(qi), tuple(mi)) for qi, mi in zip(q.tolist(), mag.tolist())])
    # Two formulations (the field turned by the whole q, against pitch and roll then eq. 14-15): ~30
    # operations each, a few ulp on the field's components, which the heading divides by the horizontal
    # field's share of the reading (≥ 1e-3 for all but ~1e-6 of random fields): ≲ 1e-12 rad; 1e-9 leaves room.
    np.testing.assert_allclose(np.angle(np.exp(1j * (got - expected))), 0.0, atol=1e-9)

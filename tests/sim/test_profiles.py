"""Truth profiles are physically consistent: rates integrate to the attitudes, derivatives agree."""

import math

import numpy as np
import pytest

from groundstation import quaternion as quat
from groundstation.sim.profiles import PROFILES, REST_S, make_profile

DURATION_S = 40.0


@pytest.mark.parametrize("name", PROFILES)
def test_integrating_truth_rates_reproduces_truth_quaternions(name):
    profile = make_profile(name, DURATION_S, seed=3)
    t = np.arange(0.0, DURATION_S, 0.01)
    q = profile.truth(t).q_body_to_ned
    # Integrate every 10 ms interval independently from the truth at its start, 50 midpoint substeps.
    q_int = q[:-1]
    h = 0.01 / 50
    for j in range(50):
        rate = profile.truth(t[:-1] + (j + 0.5) * h).rate_body_rad_s
        q_int = quat.multiply(q_int, quat.from_rotation_vector(rate * h))
    error = quat.angle_between(q_int, q[1:])
    assert np.max(error) < 1e-6, np.degrees(np.max(error))


@pytest.mark.parametrize("name", PROFILES)
def test_linear_motion_derivatives_agree_and_the_start_is_at_rest(name):
    profile = make_profile(name, DURATION_S, seed=4)
    h = 1e-5  # small against the hover profile's 300 Hz vibration harmonic
    t = np.linspace(REST_S, DURATION_S, 2001)
    before, now, after = profile.truth(t - h), profile.truth(t), profile.truth(t + h)
    vel_fd = (after.pos_ned_m - before.pos_ned_m) / (2 * h)
    acc_fd = (after.vel_ned_m_s - before.vel_ned_m_s) / (2 * h)
    assert np.allclose(vel_fd, now.vel_ned_m_s, atol=1e-5)
    assert np.allclose(acc_fd, now.acc_ned_m_s2, atol=1e-3 * max(1.0, np.abs(now.acc_ned_m_s2).max()))
    rest = profile.truth(np.linspace(0.0, REST_S, 50))
    assert np.abs(rest.rate_body_rad_s).max() == 0.0 and np.abs(rest.acc_ned_m_s2).max() == 0.0
    assert np.allclose(rest.q_body_to_ned, quat.IDENTITY)


def test_profiles_do_what_their_names_say():
    t = np.arange(0.0, 600.0, 0.01)
    euler = lambda tr: np.degrees(quat.to_euler_zyx(tr.q_body_to_ned))  # noqa: E731
    static = make_profile("static", 600.0, 1).truth(t)
    assert np.abs(static.rate_body_rad_s).max() == 0 and np.abs(static.acc_ned_m_s2).max() == 0
    slide = make_profile("slide", 600.0, 1).truth(t)
    assert np.abs(slide.q_body_to_ned - quat.IDENTITY).max() == 0.0  # true pitch is exactly 0
    assert 2.5 < np.abs(slide.acc_ned_m_s2[:, 0]).max() <= 3.0 + 1e-9
    flight = make_profile("flight", 600.0, 1).truth(t)
    angles = euler(flight)
    assert 25.0 < np.abs(angles[:, 1]).max() <= 30.0 + 1e-9 and 25.0 < np.abs(angles[:, 2]).max() <= 30.0 + 1e-9
    assert np.ptp(-flight.pos_ned_m[:, 2]) > 5.0  # climbs
    fast = make_profile("fast", 600.0, 1).truth(t)
    assert np.degrees(np.abs(fast.rate_body_rad_s).max()) > 550.0
    aggressive = make_profile("aggressive", 600.0, 1).truth(t)
    rate_dps = np.degrees(np.linalg.norm(aggressive.rate_body_rad_s[t >= REST_S], axis=1))
    assert rate_dps[: len(rate_dps) // 150 * 150].reshape(-1, 150).max(axis=1).min() > 20.0  # never still for 1.5 s
    assert np.median(rate_dps) > 50.0 and rate_dps.max() > 250.0
    hover = make_profile("hover", 600.0, 1).truth(t)
    assert np.abs(euler(hover)[:, 1:]).max() < 5.0


def test_same_seed_same_truth_other_seed_other_truth_and_hours_are_cheap():
    t = np.arange(0.0, 3600.0, 0.01)
    a = make_profile("flight", 3600.0, 7).truth(t)
    b = make_profile("flight", 3600.0, 7).truth(t)
    c = make_profile("flight", 3600.0, 8).truth(t)
    assert np.array_equal(a.q_body_to_ned, b.q_body_to_ned)
    assert not np.array_equal(a.q_body_to_ned, c.q_body_to_ned)
    assert math.isfinite(a.rate_body_rad_s.sum())


def test_bad_profile_or_duration_is_refused():
    with pytest.raises(ValueError, match="unknown profile"):
        make_profile("loop", 10.0)
    with pytest.raises(ValueError, match="positive"):
        make_profile("static", 0.0)

"""Every estimator behind the one interface: run = step, physical sanity, robust stepping."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from estimation_samples import flight_like_samples
from groundstation import quaternion
from groundstation.estimation import ESTIMATORS, create, parse_overrides, runnable
from groundstation.estimation import base

NAMES = list(ESTIMATORS)


def chatter_deg(name, dt_s=0.01):
    """How far one sample may move ahf/hf at rest: eq. 18 normalises the gradient, so even a rounding-size
    error gets a full λ Δt (hfm: β Δt) quaternion step, i.e. a turn of 2 λ Δt rad. The other filters' corrections
    scale with the error, so they sit still (0.05 deg covers rounding)."""
    lam = {"ahf": create("ahf").settings.lambda_max, "hf": create("hf").settings.beta, "hfm": create("hfm").settings.beta}.get(name)
    return 0.05 if lam is None else math.degrees(2.0 * lam * dt_s) + 0.05


def euler_deg(q):
    return np.degrees(quaternion.to_euler_zyx(np.asarray(q, dtype=float)))


def static_acc(pitch_deg, roll_deg):
    """Specific force (g) at rest in body FRD axes, from scipy (independent of our quaternion code)."""
    r = Rotation.from_euler("ZYX", [0.0, pitch_deg, roll_deg], degrees=True)
    return r.inv().apply([0.0, 0.0, -1.0])  # the earth's "up" reaction, in body axes


def test_every_estimator_describes_itself():
    """Its own name, a label no other has, and only needs the sessions know (what ``runnable`` checks)."""
    assert all(ESTIMATORS[name].name == name for name in NAMES)
    labels = [ESTIMATORS[name].label for name in NAMES]
    assert len(set(labels)) == len(labels)
    assert set().union(*(cls.needs for cls in ESTIMATORS.values())) <= {"mag", "gps"}
    assert runnable(set(), NAMES) == tuple(n for n in NAMES if not ESTIMATORS[n].needs)
    assert set(runnable({"mag"}, NAMES)) == set(NAMES) - {"ukf", "sssrukf"}


@pytest.mark.parametrize("name", NAMES)
def test_run_returns_exactly_what_step_returns(name):
    gyr, acc, dt = flight_like_samples(400, seed=11)
    acc[50] = np.nan  # the robust paths too
    dt[60] = -1.0
    stepper, batch = create(name), create(name)
    stepped = [stepper.step(g, a, d) for g, a, d in zip(gyr.tolist(), acc.tolist(), dt.tolist())]
    q, diag = batch.run(gyr, acc, dt)
    np.testing.assert_array_equal(q, np.array([s[0] for s in stepped]))
    for i, field in enumerate(type(stepped[0][1])._fields):
        np.testing.assert_array_equal(diag[field], [s[1][i] for s in stepped])


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("pitch_deg, roll_deg", [(30.0, 0.0), (0.0, 20.0), (-45.0, 60.0), (10.0, 180.0)])
def test_static_attitude_reads_right_from_the_first_sample_and_stays(name, pitch_deg, roll_deg):
    # 30 deg nose-up reads pitch +30; a 20 deg right bank reads roll +20; upside down is not a problem.
    est = create(name)
    acc = static_acc(pitch_deg, roll_deg)
    q, _ = est.run(np.zeros((300, 3)), np.tile(acc, (300, 1)), 0.01)
    tol = chatter_deg(name)
    # A turn of tol moves pitch by at most tol, roll by at most tol / cos(pitch) (Euler rates, to first order)
    roll_tol = tol / math.cos(math.radians(pitch_deg))
    for row in (q[0], q[-1]):
        yaw, pitch, roll = euler_deg(row)
        assert pitch == pytest.approx(pitch_deg, abs=tol)
        assert math.remainder(roll - roll_deg, 360.0) == pytest.approx(0.0, abs=roll_tol)


@pytest.mark.parametrize("name", NAMES)
def test_rest_with_sensor_noise_does_not_drift(name):
    # 60 s at 100 Hz, level, MPU-6050 datasheet noise (0.005 deg/s/sqrt(Hz), 400 ug/sqrt(Hz)) and a
    # calibrated gyro: pitch and roll stay put.
    rng = np.random.default_rng(12)
    n, rate = 6000, 100.0
    gyr = rng.normal(0.0, math.radians(0.005) * math.sqrt(rate / 2), (n, 3))
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 400e-6 * math.sqrt(rate / 2), (n, 3))
    q, _ = create(name).run(gyr, acc, 1.0 / rate)
    _, pitch, roll = euler_deg(q[-1000:]).T
    assert abs(pitch.mean()) < 0.05 and abs(roll.mean()) < 0.05  # no drift
    # Jitter: the per-step chatter plus what 3 sigma of accelerometer noise (8.5 mg, 0.5 deg) can pull.
    assert np.abs(pitch).max() < chatter_deg(name) + 0.5 and np.abs(roll).max() < chatter_deg(name) + 0.5


@pytest.mark.parametrize("name", NAMES)
def test_tracks_a_synthetic_rotation_with_exact_sensors(name):
    """Truth from scipy: a smooth tumble; the gyro is the exact body rate and the accelerometer exact gravity."""
    rate, seconds = 100.0, 20.0
    t = np.arange(0.0, seconds, 1.0 / rate)
    angles = np.column_stack([40 * np.sin(0.3 * t), 25 * np.sin(0.5 * t + 1), 35 * np.sin(0.4 * t + 2)])
    truth = Rotation.from_euler("ZYX", angles, degrees=True)
    # Body rate over each interval, from the relative rotation (exact for constant rate in between).
    rel = (truth[:-1].inv() * truth[1:]).as_rotvec() * rate
    gyr = np.vstack([rel[:1], rel])
    acc = truth.inv().apply([0.0, 0.0, -1.0])
    q, _ = create(name).run(gyr, acc, 1.0 / rate)
    est_down = quaternion.rotate(quaternion.conjugate(q), [0.0, 0.0, 1.0])
    true_down = truth.inv().apply([0.0, 0.0, 1.0])
    err_deg = np.degrees(np.arccos(np.clip(np.sum(est_down * true_down, axis=1), -1, 1)))
    assert np.sqrt(np.mean(err_deg**2)) < 0.5 * chatter_deg(name) + 0.5
    assert err_deg.max() < chatter_deg(name) + 1.0


BAD = {
    "gyro nan": ([np.nan, 0.0, 0.0], [0.0, 0.0, -1.0], 0.01, base.HELD),
    "gyro inf": ([0.0, np.inf, 0.0], [0.0, 0.0, -1.0], 0.01, base.HELD),
    "dt zero": ([0.1, 0.0, 0.0], [0.0, 0.0, -1.0], 0.0, base.HELD),
    "dt negative": ([0.1, 0.0, 0.0], [0.0, 0.0, -1.0], -0.01, base.HELD),
    "dt nan": ([0.1, 0.0, 0.0], [0.0, 0.0, -1.0], np.nan, base.HELD),
    "acc nan": ([0.1, 0.0, 0.0], [np.nan, 0.0, -1.0], 0.01, base.ACC_SKIPPED),
    "acc inf": ([0.1, 0.0, 0.0], [0.0, -np.inf, -1.0], 0.01, base.ACC_SKIPPED),
    "free fall": ([0.1, 0.0, 0.0], [0.0, 0.01, -0.02], 0.01, base.ACC_SKIPPED),
    # One 15 g sample is used: only a low-passed deviation skips the accelerometer (base.py).
    "shock": ([0.1, 0.0, 0.0], [8.0, 3.0, -12.0], 0.01, 0),
    "gyro at +-2000 dps full scale": ([34.9, -34.9, 34.9], [0.0, 0.0, -1.0], 0.01, 0),
}


@pytest.mark.parametrize("case", list(BAD))
@pytest.mark.parametrize("name", NAMES)
def test_bad_samples_never_produce_nan(name, case):
    gyr, acc, dt, flag = BAD[case]
    est = create(name)
    q_before, _ = est.step([0.0, 0.0, 0.0], static_acc(10.0, -5.0), 0.01)
    q, diag = est.step(gyr, acc, dt)
    assert np.all(np.isfinite(q)) and abs(np.linalg.norm(q) - 1.0) < 1e-9
    assert all(np.isfinite(v) for v in diag[1:])
    assert (diag.status & flag) == flag
    if flag == base.HELD:
        assert q == q_before
    if flag == base.ACC_SKIPPED:
        # The gyro alone moved the estimate: roll rate 0.1 rad/s for 10 ms.
        assert quaternion.angle_between(q_before, q) == pytest.approx(0.001, rel=0.05)
    # And the filter carries on normally afterwards.
    q, diag = est.step([0.0, 0.0, 0.0], static_acc(10.0, -5.0), 0.01)
    assert np.all(np.isfinite(q)) and diag.status & (base.HELD | base.ACC_SKIPPED) == 0


@pytest.mark.parametrize("name", NAMES)
def test_waits_for_a_usable_accelerometer_before_initialising(name):
    est = create(name)
    q, diag = est.step([0.1, 0.0, 0.0], [np.nan, np.nan, np.nan], 0.01)
    assert q == (1.0, 0.0, 0.0, 0.0) and diag.status == base.WAITING
    q, diag = est.step([0.0, 0.0, 0.0], static_acc(-20.0, 0.0), 0.01)
    assert diag.status & base.INITIALISED
    assert euler_deg(q)[1] == pytest.approx(-20.0, abs=chatter_deg(name))


@pytest.mark.parametrize("name", NAMES)
def test_long_gap_reinitialises_tilt_and_keeps_yaw(name):
    est = create(name)
    est.step([0.0, 0.0, 0.0], static_acc(0.0, 0.0), 0.01)
    for _ in range(100):  # yaw to about +57 deg at 1 rad/s
        est.step([0.0, 0.0, 1.0], static_acc(0.0, 0.0), 0.01)
    yaw_before = euler_deg(est.step([0.0, 0.0, 0.0], static_acc(0.0, 0.0), 0.01)[0])[0]
    # Three seconds of lost frames; meanwhile the craft was tilted. A huge stale rate must not be integrated.
    q, diag = est.step([5.0, 5.0, 5.0], static_acc(25.0, -15.0), 3.0)
    assert diag.status & base.REINITIALISED
    yaw, pitch, roll = euler_deg(q)
    assert (pitch, roll) == (pytest.approx(25.0, abs=0.05), pytest.approx(-15.0, abs=0.05))
    assert yaw == pytest.approx(yaw_before, abs=0.05)


def test_settings_are_frozen_and_overrides_are_checked():
    est = create("hf", {"beta": 0.033})
    assert est.settings.beta == 0.033
    with pytest.raises(dataclasses.FrozenInstanceError):
        est.settings.beta = 1.0
    with pytest.raises(ValueError, match="no setting 'bta'"):
        create("hf", {"bta": 1.0})
    with pytest.raises(ValueError, match="unknown estimator"):
        create("madgwick")
    assert parse_overrides(["hf.beta=0.033", "ahf.lambda_min=0.1", "hf.acc_max_g=4"]) == {
        "hf": {"beta": 0.033, "acc_max_g": 4.0},
        "ahf": {"lambda_min": 0.1},
    }
    for bad in ["hf.beta", "beta=1", "hf.beta=abc", ".beta=1"]:
        with pytest.raises(ValueError):
            parse_overrides([bad])


@pytest.mark.parametrize("name", NAMES)
def test_an_infinite_period_leaves_the_deviation_gate_working(name):
    """dt_s = inf is held like NaN; with the low-passed deviation gate on it used to make the deviation
    inf/inf = NaN, and NaN <= limit skipped the accelerometer on every later sample until a reset."""
    est = create(name, {"acc_deviation_max_g": 0.3})
    level = static_acc(0.0, 0.0)
    est.step([0.0, 0.0, 0.0], level, 0.01)
    _, diag = est.step([0.0, 0.0, 0.0], level, math.inf)
    assert diag.status & base.HELD
    statuses = [est.step([0.0, 0.0, 0.0], level, 0.01)[1].status for _ in range(50)]
    assert not any(s & base.ACC_SKIPPED for s in statuses)

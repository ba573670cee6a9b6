"""HFM and ECFM: the magnetometer turns them about the vertical only, their fall-back to the IMU filters, and
yaw against truth. (Their IMU parts are checked against ahrs in test_oracles.py; ahrs's MARG filters let the
field tilt the estimate, which these do not: test_magnetic_disturbance.py.)"""

import math

import numpy as np
import pytest
from estimation_samples import random_samples

from groundstation import quaternion as quat
from groundstation.estimation.ahf import Hf, HfSettings
from groundstation.estimation.ecf import Ecf, EcfSettings
from groundstation.estimation.magcal import fit
from groundstation.estimation.marg import Ecfm, Hfm
from groundstation.sim.offline import simulate

Q0 = quat.normalise([0.9, 0.1, -0.3, 0.2])


def random_fields(n, seed):
    """Readings in µT of random direction and a field-like strength."""
    rng = np.random.default_rng(seed)
    m = rng.normal(0.0, 1.0, (n, 3))
    return m * rng.uniform(20.0, 60.0, (n, 1)) / np.linalg.norm(m, axis=1, keepdims=True)


def test_the_magnetometer_turns_the_estimate_about_the_vertical_only():
    """One step from random attitudes with a random field reading, against the same step of the IMU twin
    (Hf, Ecf): the estimates are apart by a turn about the NED vertical (issue 33: Madgwick's and
    Mahony's published MARG terms tilt too, so a magnet near the sensor moved pitch and roll). The
    Euler step mixes the two corrections to second order, (λ Δt)² = 2.5e-5 rad here, against a
    first-order tilt of λ Δt = 5e-3 rad from the published terms."""
    rng = np.random.default_rng(21)
    fields = random_fields(200, seed=22)
    turned = 0
    for field in fields:
        q0 = quat.normalise(rng.normal(size=4))
        down_body = quat.rotate(quat.conjugate(q0), [0.0, 0.0, 1.0])
        acc = tuple(-down_body + rng.normal(0.0, 0.05, 3))  # a gravity error as well
        for est, twin in ((Hfm(HfSettings(beta=0.5)), Hf(HfSettings(beta=0.5))), (Ecfm(EcfSettings(kp=0.5, ki=0.5)), Ecf(EcfSettings(kp=0.5, ki=0.5)))):
            est.reset(q0)
            twin.reset(q0)
            q, _ = est.step((0.0, 0.0, 0.0), acc, 0.01, mag=tuple(field))
            q_twin, _ = twin.step((0.0, 0.0, 0.0), acc, 0.01)
            turn = quat.multiply(np.array(q), quat.conjugate(np.array(q_twin)))
            assert np.hypot(turn[1], turn[2]) < 5e-5, est.name
            turned += abs(turn[3]) > 5e-5
    assert turned > 300  # the field did turn heading on almost every sample


def test_without_a_usable_reading_they_are_the_imu_filters():
    gyr, acc, dt = random_samples(500, seed=15)
    mag = random_fields(500, seed=16)
    mag[::2] = np.nan  # no reading
    mag[1::4] = [np.nan, 1.0, 2.0]  # a damaged reading
    mag[3::8] = 0.0
    mag[7::8] = [np.inf, 0.0, 0.0]
    for marg, imu in ((Hfm(), Hf()), (Ecfm(), Ecf())):
        marg.reset(Q0)
        imu.reset(Q0)
        assert np.array_equal(marg.run(gyr, acc, dt, mag=mag)[0], imu.run(gyr, acc, dt)[0])


def test_yaw_turns_to_truth_from_a_wrong_start_on_a_simulated_flight():
    """Hover with mag (hard iron removed by the ellipsoid fit of a calibration flight of the same part),
    started 60° off in yaw: the magnetometer term brings yaw to truth; the IMU filter stays off. From the
    default start (yaw from the compass) they are at truth throughout."""
    cal = fit(np.vstack([simulate(name, 60.0, seed=3, mag_rate_hz=100).mag_ut for name in ("flight", "fast")]))
    run = simulate("hover", 90.0, seed=3, mag_rate_hz=100)
    mag = cal.apply(run.mag_ut)
    yaw_true = quat.to_euler_zyx(run.truth.q_body_to_ned)[:, 0]
    settled = run.truth.t_s > 60.0  # ECF's PI loop on yaw rings for ~40 s after a 60° error
    q_wrong = quat.from_euler_zyx(math.radians(60.0), 0.0, 0.0)

    def yaw_rms_deg(est, q0=q_wrong, samples=settled):
        est.reset(q0)
        q, _ = est.run(run.gyr_rad_s, run.acc_g, run.dt_s, mag=mag)
        err = np.angle(np.exp(1j * (quat.to_euler_zyx(q)[:, 0] - yaw_true)))
        return np.degrees(np.sqrt(np.mean(err[samples] ** 2)))

    # hfm's tilt is HF's (2.8° RMS in this hover; ECF's 1.1°), and a tilt error turns the compass heading by
    # up to tan(dip) ≈ 2.2 times it here: the magnetometer corrects heading only (issue 33)
    for est, limit_deg in ((Hfm(), 5.0), (Ecfm(), 3.0)):
        assert yaw_rms_deg(est) < limit_deg, est.name
        assert yaw_rms_deg(est, None, slice(None)) < limit_deg, est.name
    assert yaw_rms_deg(Hf()) > 50.0


def test_first_sample_with_a_reading_sets_yaw_from_the_compass():
    yaw = math.radians(40.0)
    field_body = quat.rotate(quat.conjugate(quat.from_euler_zyx(yaw, 0.0, 0.0)), [20.0, 0.0, 45.0])
    for est in (Hfm(), Ecfm()):
        q, _ = est.step((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 0.01, mag=tuple(field_body))
        assert quat.to_euler_zyx(np.array(q))[0] == pytest.approx(yaw, abs=1e-3)  # then one 10-ms update


@pytest.mark.parametrize(("trial_name", "limit_deg"), [("02_undisturbed_slow_rotation_B", 1.4), ("16_undisturbed_fast_translation_B", 4.0)])
def test_hfm_heading_is_not_skewed_by_its_tilt_error(broad_dir, trial_name, limit_deg):
    """BROAD dev trials without disturbance, heading as ``evaluate`` scores it: the field's step normalised on
    its own turned heading at β whatever the error, after each compass heading that the tilt error skews
    (× tan 68° on these trials): 1.66° and 6.75° RMS, where Madgwick's share of the step gives 1.22° and 2.77°
    (and 1.15°, 2.42° when the field also tilted the estimate, issue 33 item 4)."""
    from groundstation.datasets import read_csv
    from groundstation.estimation.evaluation import evaluate_trial

    figures = evaluate_trial(read_csv(broad_dir / f"{trial_name}.csv.gz"), ["hfm"])["hfm"]
    assert figures["heading_rmse_deg"] < limit_deg, figures

"""HFM and ECFM against ahrs's MARG filters, their fall-back to the IMU filters, and yaw against truth.

Frames as in test_oracles.py. ahrs's Madgwick puts the field's horizontal part on earth +x (north). ahrs's Mahony gets ``-acc`` (its reference direction is then our down) and puts the field on
earth +y, so its earth frame is (west, north, down): ``q_ned = qz(-90°) ⊗ q_ahrs``.
"""

import math

import numpy as np
import pytest
from ahrs.filters import Madgwick, Mahony
from estimation_samples import random_samples

from groundstation import quaternion as quat
from groundstation.estimation.ahf import Hf, HfSettings
from groundstation.estimation.ecf import Ecf, EcfSettings
from groundstation.estimation.magcal import fit
from groundstation.estimation.marg import Ecfm, Hfm
from groundstation.sim.offline import simulate

Q0 = quat.normalise([0.9, 0.1, -0.3, 0.2])
TO_NED = quat.from_euler_zyx(-math.pi / 2, 0.0, 0.0)  # ahrs Mahony's (W, N, D) earth frame -> NED


def random_fields(n, seed):
    """Readings in µT of random direction and a field-like strength."""
    rng = np.random.default_rng(seed)
    m = rng.normal(0.0, 1.0, (n, 3))
    return m * rng.uniform(20.0, 60.0, (n, 1)) / np.linalg.norm(m, axis=1, keepdims=True)


def test_hfm_agrees_with_ahrs_madgwick_marg():
    """Hovering (small errors, where ahrs's step has no radial part to speak of: ahf.py on the tangent
    projection), the sensor turned to read +1 g on z so ahrs runs upright, fed as it is; ahrs's earth
    frame (north, west, up) is NED after a half turn about x."""
    run = simulate("hover", 30.0, seed=2, mag_rate_hz=100.0)
    flip = np.array([1.0, -1.0, -1.0])
    gyr, acc, mag, dt = run.gyr_rad_s * flip, run.acc_g * flip, run.mag_ut * flip, run.dt_s
    half_turn = np.array([0.0, 1.0, 0.0, 0.0])
    hfm = Hfm(HfSettings(beta=0.3))
    q, _ = hfm.run(gyr, acc, dt, mag=mag)
    filt, qr, ref = Madgwick(gain=0.3), quat.multiply(half_turn, q[0]), [q[0]]
    for g, a, m in zip(gyr[1:], acc[1:], mag[1:]):
        qr = filt.updateMARG(qr, g, a, m, dt=dt)
        ref.append(quat.multiply(half_turn, qr))
    apart = np.degrees(2 * np.arccos(np.abs(np.sum(q * np.array(ref), axis=1)).clip(max=1.0)))
    assert np.median(apart) < 0.01 and np.percentile(apart, 90) < 0.05, np.percentile(apart, [50, 90, 100])


def test_ecfm_equals_ahrs_mahony_marg():
    gyr, acc, dt = random_samples(3_000, seed=13)
    mag = random_fields(3_000, seed=14)
    ecfm = Ecfm(EcfSettings(kp=0.8, ki=0.2, bias_max_rad_s=math.inf, error_max=math.inf))  # bounds off: Mahony as published
    ecfm.reset(Q0)
    q, diag = ecfm.run(gyr, acc, dt, mag=mag)
    filt, ref, bias = Mahony(k_P=0.8, k_I=0.2), [], []
    qr = quat.multiply(quat.conjugate(TO_NED), Q0)
    for g, a, m, d in zip(gyr, acc, mag, dt):
        qr = filt.updateMARG(qr, g, -a, m, dt=d)
        ref.append(qr)
        bias.append(filt.b.copy())
    np.testing.assert_allclose(q, quat.multiply(TO_NED, np.array(ref)), atol=1e-9, rtol=0)
    np.testing.assert_allclose(np.column_stack([diag[f"bias_{k}_rad_s"] for k in "xyz"]), bias, atol=1e-9)


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

    for est in (Hfm(), Ecfm()):
        assert yaw_rms_deg(est) < 3.0, est.name
        assert yaw_rms_deg(est, None, slice(None)) < 3.0, est.name
    assert yaw_rms_deg(Hf()) > 50.0


def test_first_sample_with_a_reading_sets_yaw_from_the_compass():
    yaw = math.radians(40.0)
    field_body = quat.rotate(quat.conjugate(quat.from_euler_zyx(yaw, 0.0, 0.0)), [20.0, 0.0, 45.0])
    for est in (Hfm(), Ecfm()):
        q, _ = est.step((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), 0.01, mag=tuple(field_body))
        assert quat.to_euler_zyx(np.array(q))[0] == pytest.approx(yaw, abs=1e-3)  # then one 10-ms update

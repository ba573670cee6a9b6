"""Each estimator against an independent implementation: ahrs (Madgwick, Mahony, EKF) and numpy.

Frames: ahrs's filters take the specific force with earth z up; ours take it in body FRD with earth NED
(z down). Feeding ahrs ``-acc`` makes its reference direction our down direction (Mahony, EKF: the
quaternions must agree). Madgwick is compared on data it runs upright (ahf.py on the tangent
projection): a sensor reading +1 g on z, fed as it is, its earth frame turned to NED by a half turn
about x.
"""

import math

import numpy as np
import pytest
from ahrs.filters import EKF, Madgwick, Mahony
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

from groundstation import quaternion
from groundstation.estimation.evaluation import inclination_error_rad
from groundstation.sim.offline import simulate

from groundstation.estimation import Ahf, Ecf, Ekf, Hf
from groundstation.estimation.ahf import AhfSettings, HfSettings
from groundstation.estimation.ecf import EcfSettings
from estimation_samples import flight_like_samples, random_samples

Q0 = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])


X_HALF_TURN = np.array([0.0, 1.0, 0.0, 0.0])  # ahrs's earth frame (z up) <-> NED: a half turn about x


def reading_plus_g_on_z(gyr, acc, dt):
    """Samples turned 180° about x: the sensor reads +1 g on z at rest, as BROAD's does. Fed as they
    are, ahrs's Madgwick (reference earth z up, specific force) runs its sensor upright."""
    return gyr * [1, -1, -1], acc * [1, -1, -1], dt


def ahrs_madgwick(gyr, acc, dt, gains, q0):
    """ahrs Madgwick from our ``q0`` (body -> NED), its output turned back into NED."""
    filt, q, out = Madgwick(), quaternion.multiply(X_HALF_TURN, q0), []
    for g, a, d, gain in zip(gyr, acc, dt, gains):
        filt.gain = gain
        q = filt.updateIMU(q, g, a, dt=d)
        out.append(q)
    return quaternion.multiply(X_HALF_TURN, np.array(out))


def angle_deg(p, q):
    """Inclination difference (yaw is unobservable and drifts apart with any difference in the steps)."""
    return np.degrees(inclination_error_rad(p, q, truth_frame="NED"))


def test_hf_step_is_the_normalised_gradient_on_the_unit_sphere():
    """One HF step with the gyro still is q - β Δt ∇F/‖∇F‖, ∇F the gradient of F(q) = ½‖ĝ(q) - â‖²
    along the unit sphere, here by central differences through scipy's rotations (ĝ = Rᵀ e_z)."""
    rng = np.random.default_rng(1)
    beta, dt = 0.3, 0.01
    for _ in range(200):
        q0 = quaternion.normalise(rng.normal(size=4))
        acc = rng.normal(size=3)
        acc *= rng.uniform(0.5, 2.0) / np.linalg.norm(acc)  # inside the guards
        down = -acc / np.linalg.norm(acc)

        def cost(q):
            g_est = Rotation.from_quat(q, scalar_first=True).inv().apply([0.0, 0.0, 1.0])
            return 0.5 * np.sum((g_est - down) ** 2)

        h = 1e-6
        grad = np.array([(cost(q0 + h * e) - cost(q0 - h * e)) / (2 * h) for e in np.eye(4)])
        grad -= grad.dot(q0) * q0  # along the sphere
        expected = quaternion.normalise(q0 - beta * dt * grad / np.linalg.norm(grad))
        hf = Hf(HfSettings(beta=beta))
        hf.reset(q0)
        q, _ = hf.step((0.0, 0.0, 0.0), tuple(acc), dt)
        np.testing.assert_allclose(q, expected, atol=1e-8)


def test_hf_agrees_with_ahrs_madgwick_on_a_sensor_reading_plus_g_on_z():
    """On a hovering craft (small tilts and errors, where ahrs's radial part, of second order in the error
    and zero when its estimate is upright, vanishes: ahf.py) the two agree closely."""
    run = simulate("hover", 30.0, seed=1)
    gyr, acc, dt = reading_plus_g_on_z(run.gyr_rad_s, run.acc_g, np.full(len(run), run.dt_s))
    q0 = np.array(Hf._attitude_from_acc(*acc[0], 0.0))
    hf = Hf(HfSettings(beta=0.3))
    hf.reset(q0)
    q, _ = hf.run(gyr, acc, dt)
    apart = angle_deg(q, ahrs_madgwick(gyr, acc, dt, np.full(len(dt), 0.3), q0))
    assert np.median(apart) < 0.005 and np.percentile(apart, 90) < 0.01 and apart.max() < 1.0


def test_ahf_is_madgwick_with_the_lambda_of_eq_20():
    """λ recomputed independently (numpy + scipy's lfilter for the low-pass), then Madgwick with that λ."""
    gyr, acc, dt = reading_plus_g_on_z(*flight_like_samples(3_000, seed=2))
    q0 = np.array(Hf._attitude_from_acc(*acc[0], 0.0))
    ahf = Ahf()
    ahf.reset(q0)
    q, diag = ahf.run(gyr, acc, dt)
    prior = np.vstack([q0, q[:-1]])
    w, x, y, z = prior.T
    g_est = np.column_stack([2 * (x * z - w * y), 2 * (w * x + y * z), w * w - x * x - y * y + z * z])
    a = -acc / np.linalg.norm(acc, axis=1, keepdims=True)
    err = np.abs(np.cross(g_est, a)).sum(axis=1)
    e_a = lfilter([0.1 * 10.0], [1.0, -0.9], err)
    lam = np.clip(2.0 - e_a, 0.2, 2.0)
    np.testing.assert_allclose(diag["lam"], lam, atol=1e-12)
    assert lam.min() == 0.2 and lam.max() > 1.0  # the random inputs exercise both the clamp and the range
    # Rough data, errors up to tens of degrees: ahrs's second-order radial part shows (ahf.py)
    assert np.median(angle_deg(q, ahrs_madgwick(gyr, acc, dt, lam, q0))) < 0.5


def test_ahf_gyro_overrange_rule_forces_lambda_max():
    gyr, acc, dt = flight_like_samples(500, seed=3)
    limit = 0.4
    ahf = Ahf(AhfSettings(gyro_overrange_rad_s=limit))
    ahf.reset(Q0)
    _, diag = ahf.run(gyr, acc, dt)
    over = np.abs(gyr).max(axis=1) >= limit
    assert over.any() and (~over).any()
    assert np.all(diag["lam"][over] == 2.0)
    assert np.all((diag["status"][over] & 32) != 0) and np.all((diag["status"][~over] & 32) == 0)
    assert diag["lam"][~over].min() < 2.0


def test_ecf_equals_ahrs_mahony():
    # Same scheme as ahrs: the bias integral is updated before it is used, then one Euler step.
    gyr, acc, dt = random_samples(5_000, seed=4)
    ecf = Ecf(EcfSettings(kp=0.8, ki=0.2, bias_max_rad_s=math.inf, error_max=math.inf))  # bounds off: Mahony as published
    ecf.reset(Q0)
    q, diag = ecf.run(gyr, acc, dt)
    filt, ref, bias = Mahony(k_P=0.8, k_I=0.2), [], []
    qr = Q0.copy()
    for g, a, d in zip(gyr, acc, dt):
        qr = filt.updateIMU(qr, g, -a, dt=d)
        ref.append(qr)
        bias.append(filt.b.copy())
    np.testing.assert_allclose(q, np.array(ref), atol=1e-9, rtol=0)
    np.testing.assert_allclose(np.column_stack([diag["bias_x_rad_s"], diag["bias_y_rad_s"], diag["bias_z_rad_s"]]), bias, atol=1e-9)


def test_ekf_tracks_ahrs_ekf():
    """ahrs evaluates H on the unnormalised prediction; we normalise first (ekf.py): O((ω dt)²) apart.
    ahrs normalises the accelerometer, ekf.py does not: readings of exactly 1 g, the same to both."""
    rng = np.random.default_rng(5)
    n = 2_000
    gyr = rng.normal(0.0, 0.5, (n, 3))
    acc = rng.normal(0.0, 0.05, (n, 3)) + [0.0, 0.0, -1.0]
    acc /= np.linalg.norm(acc, axis=1, keepdims=True)
    dt = np.full(n, 0.01)
    ekf = Ekf()
    ekf.reset(Q0)
    q, _ = ekf.run(gyr, acc, dt)
    s = ekf.settings
    filt = EKF(frame="NED", noises=[s.gyro_noise_rad_s**2, s.acc_noise**2, 1.0], P=np.eye(4) * 0.01)
    qr, ref = Q0.copy(), []
    for g, a, d in zip(gyr, acc, dt):
        qr = filt.update(qr, g, -a, dt=d)
        ref.append(qr)
    ref = np.array(ref)
    dot = np.abs(np.sum(q * ref, axis=1)).clip(max=1.0)
    angle_deg = np.degrees(2 * np.arccos(dot))
    assert angle_deg.max() < 0.05, angle_deg.max()
    assert angle_deg.max() > 0.0  # they are not the same code


@pytest.mark.parametrize("cls", [Ahf, Hf])
def test_float32_core_stays_float32_and_each_step_matches_float64(cls):
    """Each float32 step equals a float64 step from the same state to float32 precision.

    Whole runs are not compared: eq. 18 normalises the gradient, so when the error is near zero its
    direction is set by rounding and float32 and float64 runs part by up to about λ dt (ahf.py).
    """
    gyr, acc, dt = flight_like_samples(2_000, seed=6)
    single = cls(dtype=np.float32)
    single.reset(Q0)
    worst = 0.0
    for g, a, d in zip(gyr.tolist(), acc.tolist(), dt.tolist()):
        double = cls()
        double._state[:] = single._state  # the same state (q, e_a, ...), widened exactly
        q32, diag32 = single.step(g, a, d)
        q64, _ = double.step(g, a, d)
        worst = max(worst, float(np.abs(np.array(q32, dtype=float) - q64).max()))
    assert all(type(v) is np.float32 for v in q32) and type(diag32.lam) is np.float32
    assert worst < 2e-6  # a few float32 ulps (6e-8) through one step
    assert worst > 1e-9  # it really ran in float32

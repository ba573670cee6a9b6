"""Seed 004 position filters against simulator truth and the loops' analytic properties."""

import dataclasses
import math

import numpy as np
import pytest

from groundstation import quaternion
from groundstation.estimation import create
from groundstation.position import DualChannel, SingleChannel, linear_acc_ned_m_s2
from groundstation.position import design
from groundstation.sim.offline import simulate

SETTLE = 1000  # samples (10 s) left out of the error statistics: the loops' start
FILTERS = (SingleChannel, DualChannel)


@pytest.fixture(scope="module")
def hover():
    return simulate("hover", 40.0, seed=5, baro_rate_hz=25, gps_rate_hz=10)


@pytest.fixture(scope="module")
def flight():
    return simulate("flight", 40.0, seed=6, baro_rate_hz=25, gps_rate_hz=10)


def fuse(cls, run, q=None, acc_bias_ned_m_s2=(0.0, 0.0, 0.0), gps_vel=False, **aids):
    acc = linear_acc_ned_m_s2(run.acc_g, run.truth.q_body_to_ned if q is None else q) + np.array(acc_bias_ned_m_s2)
    inputs = {"baro_alt_m": run.baro_alt_m, "gps_pos_ned_m": run.gps_pos_ned_m}
    if gps_vel:
        inputs["gps_vel_ned_m_s"] = run.gps[:, :3]
    inputs.update(aids)
    return cls().run(acc, run.dt_s, **inputs)


def raw_errors(run):
    """Height error of the barometer and horizontal error of GPS, on the samples with a reading."""
    baro, gps, pos = run.baro_alt_m, run.gps_pos_ned_m, run.truth.pos_ned_m
    b, g = ~np.isnan(baro), ~np.isnan(gps[:, 0])
    b[:SETTLE] = g[:SETTLE] = False
    return baro[b] + pos[b, 2], gps[g, :2] - pos[g, :2]


def test_linear_acceleration_matches_truth_and_quaternion_rotate(hover):
    q = hover.truth.q_body_to_ned
    acc = linear_acc_ned_m_s2(hover.acc_g, q)
    # Independent: quaternion.rotate of the specific force plus gravity.
    g = 9.80665
    np.testing.assert_allclose(acc, quaternion.rotate(q, hover.acc_g * g) + [0.0, 0.0, g], atol=1e-9)
    # Against the simulator's linear acceleration: only the IMU's noise and residual bias remain.
    err = acc - hover.truth.acc_ned_m_s2
    assert np.all(np.abs(err.mean(axis=0)) < 0.1) and np.all(err.std(axis=0) < 0.1)
    # One sample as plain floats: the same numbers, as a tuple.
    one = linear_acc_ned_m_s2(hover.acc_g[123].tolist(), q[123].tolist())
    assert isinstance(one, tuple) and np.allclose(one, acc[123], atol=1e-12)


@pytest.mark.parametrize("cls", FILTERS)
@pytest.mark.parametrize("attitude", ["truth", "ahf"])
def test_fusion_fluctuates_less_than_raw_baro_and_gps(cls, attitude, hover, flight):
    for run in (hover, flight):
        q = None if attitude == "truth" else create("ahf").run(run.gyr_rad_s, run.acc_g, run.dt_s)[0]
        pos, _ = fuse(cls, run, q)
        err = (pos - run.truth.pos_ned_m)[SETTLE:]
        baro_err, gps_err = raw_errors(run)
        assert err[:, 2].std() < 0.6 * baro_err.std()
        assert np.all(err[:, :2].std(axis=0) < 0.7 * gps_err.std(axis=0))
        assert np.abs(err).max() < 3.0  # no excursion


def test_dead_reckoning_drifts_quadratically_and_fusion_bounds_it(hover):
    bias = (0.05, -0.05, 0.05)  # m/s², on top of the simulated IMU's own
    nan = np.full(len(hover), np.nan)
    dead, _ = fuse(DualChannel, hover, acc_bias_ned_m_s2=bias, baro_alt_m=nan, gps_pos_ned_m=np.full((len(hover), 3), np.nan))
    err = np.abs(dead - hover.truth.pos_ned_m)
    t = hover.truth.t_s
    # Analytic: a constant bias b gives b t²/2; the error at T is about 4x the error at T/2.
    half, end = len(t) // 2, len(t) - 1
    assert np.all(err[end] > 0.5 * 0.05 * t[end] ** 2 / 2)
    assert np.all(err[end] / err[half] > 2.5)
    fused, _ = fuse(DualChannel, hover, acc_bias_ned_m_s2=bias)
    assert np.abs(fused - hover.truth.pos_ned_m)[SETTLE:].max() < 3.0 < err[end].min()


def test_dual_channel_integral_recovers_an_injected_bias(hover):
    bias = np.array([0.1, -0.15, 0.2])  # m/s², NED
    acc = linear_acc_ned_m_s2(hover.acc_g, hover.truth.q_body_to_ned)
    f = DualChannel()
    estimates = []
    for a, h, z in zip((acc + bias).tolist(), hover.baro_alt_m.tolist(), hover.gps_pos_ned_m.tolist()):
        f.step(a, hover.dt_s, None if math.isnan(h) else h, None if math.isnan(z[0]) else z)
        estimates.append(f.bias_ned_m_s2)
    # Truth: the injected bias plus the simulated IMU's own residual, measured against the truth's acceleration.
    native = (acc - hover.truth.acc_ned_m_s2)[SETTLE:].mean(axis=0)
    # The estimate follows the GPS noise (σ ≈ 0.2 m/s² horizontally): its mean over 30 s is the figure.
    np.testing.assert_allclose(np.mean(estimates[SETTLE:], axis=0), bias + native, atol=0.05)
    assert abs(f.bias_ned_m_s2[2] - bias[2] - native[2]) < 0.05  # barometer: tight at every instant


def test_single_channel_keeps_the_analytic_steady_error_b_over_kv(hover):
    bias = 0.3  # m/s², down
    pos, _ = fuse(SingleChannel, hover, acc_bias_ned_m_s2=(0.0, 0.0, bias))
    ref, _ = fuse(SingleChannel, hover)
    gains = SingleChannel().baro_gains
    kv = gains.kv_1_s2
    # The same run without the bias removes the noise. At a reading the loop sees the steady error
    # b / kv, and its output has taken the fraction kp Δ of it off (Δ = 0.04 s at 25 Hz).
    at_readings = ~np.isnan(hover.baro_alt_m[SETTLE:])
    steady = (pos - ref)[SETTLE:, 2][at_readings].mean()
    assert steady == pytest.approx(bias / kv * (1.0 - gains.kp_1_s * 0.04), rel=0.02)
    dual, _ = fuse(DualChannel, hover, acc_bias_ned_m_s2=(0.0, 0.0, bias))
    dual_ref, _ = fuse(DualChannel, hover)
    assert abs((dual - dual_ref)[-500:, 2].mean()) < 0.1 * bias / kv


@pytest.mark.parametrize("cls", FILTERS)
def test_error_poles_are_the_designed_ones(cls):
    f = cls()
    s = f.settings
    g = f.baro_gains
    roots = np.sort_complex(np.roots([1.0, g.kp_1_s, g.kv_1_s2, g.ki_1_s3] if g.ki_1_s3 else [1.0, g.kp_1_s, g.kv_1_s2]))
    w, z = s.baro_crossover_rad_s, s.damping
    pair = w * (-z + 1j * math.sqrt(1 - z * z))
    expected = [pair, pair.conjugate()] + ([-s.bias_pole_ratio * w] if g.ki_1_s3 else [])
    np.testing.assert_allclose(roots, np.sort_complex(np.array(expected)), atol=1e-9)


def test_crossover_rule_is_the_kalman_bucy_steady_state():
    # Riccati solution of x'' = w, z = x + v (PSDs q, r) by scipy, independently of the closed form.
    scipy_linalg = pytest.importorskip("scipy.linalg")
    q, sigma, rate = 0.3**2, 0.5, 20.0
    r = sigma**2 / rate
    p = scipy_linalg.solve_continuous_are(np.array([[0.0, 1.0], [0.0, 0.0]]).T, np.array([[1.0], [0.0]]), np.diag([0.0, q]), np.array([[r]]))
    k = p[:, 0] / r  # Kalman gains (kp, kv)
    g = design.single_channel_gains(design.crossover_rad_s(math.sqrt(q), sigma, rate), design.SQRT_HALF)
    np.testing.assert_allclose([g.kp_1_s, g.kv_1_s2], k, rtol=1e-9)


@pytest.mark.parametrize("cls", FILTERS)
def test_step_equals_run(cls, flight):
    acc = linear_acc_ned_m_s2(flight.acc_g, flight.truth.q_body_to_ned)[:1500]
    baro, gps, vel = flight.baro_alt_m[:1500], flight.gps_pos_ned_m[:1500], flight.gps[:1500, :3]
    pos, v = cls().run(acc, flight.dt_s, baro, gps, vel)
    f = cls()
    for k in range(len(acc)):
        rows = [None if np.isnan(x).all() else x.tolist() for x in (gps[k], vel[k])]
        p_k, v_k = f.step(acc[k].tolist(), flight.dt_s, None if np.isnan(baro[k]) else float(baro[k]), *rows)
        assert p_k == tuple(pos[k]) and v_k == tuple(v[k])


@pytest.mark.parametrize("cls", FILTERS)
def test_bad_input_is_skipped_and_the_estimate_recovers(cls, hover):
    n = len(hover)
    acc = linear_acc_ned_m_s2(hover.acc_g, hover.truth.q_body_to_ned)
    dt = np.full(n, hover.dt_s)
    baro, gps = hover.baro_alt_m.copy(), hover.gps_pos_ned_m.copy()
    acc[1500:1550] = np.nan  # a burst of bad IMU frames
    acc[1600, 1] = np.inf
    dt[1700], dt[1701], dt[1702] = np.nan, 0.0, -0.01
    baro[2000:2400:4] = np.inf
    gps[2500:2600:10, 0] = np.nan  # north missing on some fixes
    dt[3000] = 3.0  # seconds of lost samples: not integrated, axes re-set by the next readings
    pos, vel = cls().run(acc, dt, baro, gps)
    assert np.all(np.isfinite(pos)) and np.all(np.isfinite(vel))
    err = (pos - hover.truth.pos_ned_m)[3300:]  # 3 s after the gap
    assert np.abs(err[:, 2]).max() < 0.5 and np.abs(err[:, :2]).max() < 2.5


def test_readings_after_a_gap_reset_the_axis_and_baro_is_relative(hover):
    f = DualChannel()
    f.step((0.0, 0.0, 0.0), 0.01, baro_alt_m=250.0, gps_pos_ned_m=(10.0, -4.0, -30.0))
    p, _ = f.step((0.0, 0.0, 0.0), 0.01)
    assert p == pytest.approx((10.0, -4.0, 0.0), abs=1e-9)  # baro's first reading is 0 m down; GPS down ignored
    for _ in range(200):  # 2 s without a reading
        f.step((0.0, 0.0, 0.0), 0.01)
    p, v = f.step((0.0, 0.0, 0.0), 0.01, baro_alt_m=253.0, gps_pos_ned_m=(20.0, 0.0, 0.0), gps_vel_ned_m_s=(1.0, 0.0, 0.0))
    assert p == pytest.approx((20.0, 0.0, -3.0)) and v[0] == pytest.approx(1.0)


def test_gps_only_vertical_and_velocity_aid(flight):
    """Without a barometer GPS down aids the height; GPS velocity makes the dual channel tighter."""
    pos, _ = fuse(DualChannel, flight, baro_alt_m=None)
    err = (pos - flight.truth.pos_ned_m)[SETTLE:, 2]
    gps_err = raw_errors(flight)[1]
    assert err.std() < 0.6 * gps_err.std()
    with_vel, _ = fuse(DualChannel, flight, gps_vel=True)
    without, _ = fuse(DualChannel, flight)
    truth = flight.truth.pos_ned_m[SETTLE:]
    assert np.std(with_vel[SETTLE:] - truth) < np.std(without[SETTLE:] - truth)


def test_settings_are_checked():
    with pytest.raises(ValueError):
        DualChannel(dataclasses.replace(DualChannel.Settings(), bias_pole_ratio=0.0))
    with pytest.raises(ValueError):
        SingleChannel(dataclasses.replace(SingleChannel.Settings(), damping=-1.0))
    with pytest.raises(ValueError):
        SingleChannel(dataclasses.replace(SingleChannel.Settings(), max_gap_s=0.0))

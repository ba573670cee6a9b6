"""Allan deviation against analytic truth (IEEE Std 952-1997 annex C), an independent slow
computation, and the simulated MPU-6050's configured noise."""

import math

import numpy as np
import pytest

from groundstation import units
from groundstation.analysis.allan import FLICKER_FLOOR, allan_deviation, noise_terms
from groundstation.sim.imu import MPU6050Settings
from groundstation.sim.offline import simulate

DT_S = 0.01  # 100 Hz, the telemetry rate


def slow_allan_deviation(y, dt_s, m):
    """Overlapping Allan deviation the textbook way: moving cluster averages, half the mean square of
    the difference between averages one cluster apart."""
    means = np.convolve(y, np.ones(m) / m, mode="valid")
    return math.sqrt(0.5 * np.mean((means[m:] - means[:-m]) ** 2))


def test_matches_a_direct_cluster_average_computation():
    rng = np.random.default_rng(1)
    y = rng.normal(0.0, 1.0, 5000) + np.cumsum(rng.normal(0.0, 0.05, 5000)) + 3.0
    curve = allan_deviation(y, DT_S)
    assert list(curve.tau_s / DT_S) == [2**k for k in range(12)]  # octaves up to n // 2 = 2500
    assert list(curve.clusters) == [5000 // 2**k for k in range(12)]
    for tau_s, adev in zip(curve.tau_s, curve.adev):
        assert adev == pytest.approx(slow_allan_deviation(y, DT_S, int(round(tau_s / DT_S))), rel=1e-9)


def test_white_noise_of_known_density_reads_back():
    density = 0.005  # one-sided, °/s/√Hz: σ per sample = density · √(rate / 2)
    y = np.random.default_rng(2).normal(0.0, density * math.sqrt(0.5 / DT_S), 60000)
    curve = allan_deviation(y, DT_S)
    terms = noise_terms(curve)
    assert terms.density == pytest.approx(density, rel=0.03)
    assert terms.n_rt_hz == pytest.approx(density / math.sqrt(2.0), rel=0.03)  # σ(1 s), two-sided
    # σ(τ) = N / √τ at every cluster time with many clusters.
    short = curve.clusters >= 100
    np.testing.assert_allclose(curve.adev[short], terms.n_rt_hz / np.sqrt(curve.tau_s[short]), rtol=0.06)
    assert math.isnan(terms.k_rt_s)  # no rate random walk in white noise
    assert terms.b_tau_s == curve.tau_s[curve.tau_s <= 60000 * DT_S / 8].max()  # still falling at the last τ read
    assert terms.b_is_bound


def test_rate_random_walk_of_known_k_reads_back():
    k = 0.001  # °/s/√s
    y = np.cumsum(np.random.default_rng(3).normal(0.0, k * math.sqrt(DT_S), 60000))
    terms = noise_terms(allan_deviation(y, DT_S))
    assert terms.k_rt_s == pytest.approx(k, rel=0.05)
    assert math.isnan(terms.n_rt_hz)  # no -1/2 line in a pure random walk


def test_white_noise_plus_random_walk_has_its_floor_where_theory_puts_it():
    n_rt_hz, k = 0.02, 0.02
    rng = np.random.default_rng(4)
    y = rng.normal(0.0, n_rt_hz / math.sqrt(DT_S), 120000) + np.cumsum(rng.normal(0.0, k * math.sqrt(DT_S), 120000))
    terms = noise_terms(allan_deviation(y, DT_S))
    # σ² = N²/τ + K²τ/3 is least at τ = √3 N / K with σ² = 2 N K / √3.
    assert terms.n_rt_hz == pytest.approx(n_rt_hz, rel=0.03)
    assert terms.k_rt_s == pytest.approx(k, rel=0.15)
    assert terms.b_tau_s == pytest.approx(math.sqrt(3.0) * n_rt_hz / k, rel=0.5)  # on the octave grid
    assert terms.b * FLICKER_FLOOR == pytest.approx(math.sqrt(2.0 * n_rt_hz * k / math.sqrt(3.0)), rel=0.1)
    assert not terms.b_is_bound


def test_constant_has_zero_deviation_and_a_sine_follows_theory():
    t_s = np.arange(200000) * DT_S
    assert np.all(allan_deviation(np.full(len(t_s), 4.2), DT_S).adev <= 1e-12)
    amplitude, f0_hz = 0.3, 0.37
    curve = allan_deviation(amplitude * np.sin(2.0 * math.pi * f0_hz * t_s + 0.4), DT_S)
    x = math.pi * f0_hz * curve.tau_s
    theory = amplitude * np.sin(x) ** 2 / x  # annex C: σ(τ) = Ω0 sin²(π f0 τ) / (π f0 τ)
    use = curve.tau_s <= 20.0
    np.testing.assert_allclose(curve.adev[use], theory[use], rtol=0.01, atol=1e-3 * amplitude)


@pytest.mark.parametrize(
    ("signal", "message"),
    [(np.zeros(3), "at least 4"), (np.zeros((10, 2)), "1-D"), (np.array([0.0, 1.0, np.nan, 2.0, 3.0]), "NaN")],
)
def test_bad_signals_are_refused_with_a_reason(signal, message):
    with pytest.raises(ValueError, match=message):
        allan_deviation(signal, DT_S)
    with pytest.raises(ValueError, match="dt_s"):
        allan_deviation(np.zeros(10), 0.0)


@pytest.mark.parametrize("gyro_fs_dps", [250, 2000])
def test_simulated_mpu6050_gyro_at_rest_reads_its_datasheet_density(gyro_fs_dps):
    """The simulator's white noise is the datasheet's 0.005 °/s/√Hz (sim/imu.py). Rounding to counts
    adds, independently per sample, LSB²/12 of variance, i.e. a one-sided density LSB/√12 · √(2/rate):
    0.0003 °/s/√Hz at ±250 °/s (negligible), 0.0025 at ±2000 °/s (+12 % in quadrature)."""
    settings = MPU6050Settings()
    run = simulate("static", 300.0, seed=5, gyro_fs_dps=gyro_fs_dps)
    lsb_dps = 1.0 / units.GYRO_LSB_PER_DPS[gyro_fs_dps]
    quantisation = lsb_dps / math.sqrt(12.0) * math.sqrt(2.0 * run.dt_s)
    expected = math.hypot(settings.gyro_noise_dps_rthz, quantisation)
    for axis in range(3):
        terms = noise_terms(allan_deviation(np.degrees(run.gyr_rad_s[:, axis]), run.dt_s))
        assert terms.density == pytest.approx(expected, rel=0.03)

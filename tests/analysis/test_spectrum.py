"""The amplitude spectrum: a sine's amplitude read back (analytic truth) and scipy's periodogram as oracle."""

import numpy as np
import pytest
from scipy.signal import periodogram

from groundstation.spectrum import amplitude_spectrum

DT_S = 0.01


def test_a_sine_in_noise_peaks_at_its_amplitude_and_frequency():
    n = 10_000
    t = np.arange(n) * DT_S
    f0 = 250 / (n * DT_S)  # on a bin: 2.5 Hz
    rng = np.random.default_rng(1)
    x = 3.0 + 2.0 * np.sin(2 * np.pi * f0 * t + 0.7) + rng.normal(0.0, 0.5, n)
    f, a = amplitude_spectrum(x, DT_S)
    k = np.argmax(a)
    assert f[k] == pytest.approx(f0) and a[k] == pytest.approx(2.0, rel=0.02)
    assert a[0] < 0.05  # the mean is removed
    floor = np.median(a[(f > 10) & (f < 40)])
    assert floor == pytest.approx(0.5 * np.sqrt(3.0 / n), rel=0.3)  # σ √(2 · 1.5 / N), module docstring


def test_between_bins_the_hann_window_reads_at_most_15_percent_low():
    n = 1000
    t = np.arange(n) * DT_S
    f, a = amplitude_spectrum(np.sin(2 * np.pi * 10.05 * t), DT_S)  # half a bin off
    assert 0.84 < a.max() < 0.86  # Hann scalloping loss at half a bin: 1.42 dB, 0.849 of the amplitude


@pytest.mark.parametrize("n", [1001, 1000])
@pytest.mark.parametrize("window", ["hann", "boxcar"])
def test_equals_scipy_periodogram(n, window):
    x = np.random.default_rng(n).normal(0.0, 1.0, n).cumsum()
    f, a = amplitude_spectrum(x, DT_S, window=window)
    f_ref, power = periodogram(x, fs=1 / DT_S, window=window, detrend="constant", scaling="spectrum")
    one_sided = np.ones_like(power)
    one_sided[1 : (n + 1) // 2] = 2.0  # periodogram's power doubles these bins; amplitude² = 2 · power there
    np.testing.assert_allclose(f, f_ref)
    np.testing.assert_allclose(a, np.sqrt(power * one_sided), rtol=1e-9, atol=1e-12)


def test_linear_detrend_removes_a_ramp():
    x = 0.3 * np.arange(500) + np.sin(np.arange(500))
    _, a_lin = amplitude_spectrum(x, DT_S, detrend="linear")
    _, a_const = amplitude_spectrum(x, DT_S)
    assert a_lin[1] < 1e-3 * a_const[1]


def test_bad_input_is_refused_with_a_reason():
    with pytest.raises(ValueError, match="NaN"):
        amplitude_spectrum([1.0, np.nan, 2.0], DT_S)
    with pytest.raises(ValueError, match="at least 2"):
        amplitude_spectrum([1.0], DT_S)
    with pytest.raises(ValueError, match="positive"):
        amplitude_spectrum([1.0, 2.0], 0.0)
    with pytest.raises(ValueError, match="window"):
        amplitude_spectrum([1.0, 2.0], DT_S, window="kaiser")

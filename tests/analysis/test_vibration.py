"""The vibration spectra against scipy.signal (the oracle), and a sine's amplitude and frequency read back."""

import numpy as np
import pytest
from scipy.signal import spectrogram, welch as scipy_welch

from groundstation.analysis import vibration as vib

RATE_HZ = 400.0


def test_welch_equals_scipy_on_one_and_three_axes():
    rng = np.random.default_rng(3)
    x = rng.normal(0.0, 1.0, (5000, 3)) + np.sin(2 * np.pi * 37.3 * np.arange(5000) / RATE_HZ)[:, None]
    for nperseg in (64, 256, 255):
        f, p = vib.welch(x, RATE_HZ, nperseg)
        f_ref, p_ref = scipy_welch(x, RATE_HZ, window="hann", nperseg=nperseg, noverlap=nperseg // 2, axis=0)
        np.testing.assert_allclose(f, f_ref, rtol=1e-12)
        np.testing.assert_allclose(p, p_ref, rtol=1e-10, atol=1e-10 * p_ref.max())
        f1, p1 = vib.welch(x[:, 1], RATE_HZ, nperseg)
        np.testing.assert_allclose(p1, p_ref[:, 1], rtol=1e-10, atol=1e-10 * p_ref.max())


def test_segments_equal_scipys_spectrogram():
    rng = np.random.default_rng(4)
    x = rng.normal(0.0, 1.0, 3000)
    starts, p = vib.segment_psd(x, RATE_HZ, 128)
    f_ref, t_ref, p_ref = spectrogram(x, RATE_HZ, window="hann", nperseg=128, noverlap=64)
    np.testing.assert_allclose(p, p_ref.T, rtol=1e-10, atol=1e-10 * p_ref.max())
    np.testing.assert_allclose((starts + 64) / RATE_HZ, t_ref, rtol=1e-12)


@pytest.mark.parametrize("frequency_hz", [50.0, 50.0 + 0.5 * RATE_HZ / 512])  # on a bin, half a bin off
def test_a_sine_reads_back_at_its_frequency_and_amplitude(frequency_hz):
    t = np.arange(20_000) / RATE_HZ
    x = 2.5 * np.sin(2 * np.pi * frequency_hz * t + 0.3) + np.random.default_rng(5).normal(0.0, 0.05, len(t))
    f, p = vib.welch(x, RATE_HZ, 512)
    on_bin = vib.amplitude_from_psd(p, RATE_HZ, 512).max()
    if frequency_hz == 50.0:
        assert on_bin == pytest.approx(2.5, rel=0.01)  # exactly A on a bin (module docstring)
    table = vib.ImuTable("t", "accel", t, np.column_stack([x, x, x]))
    peak = vib.find_peaks(vib.spectrum(table))[0]
    assert peak.frequency_hz == pytest.approx(frequency_hz, abs=0.2)
    assert peak.amplitude == pytest.approx(2.5, rel=0.02)  # the lobe's power does not read low between bins


def test_segments_never_cross_a_gap():
    rng = np.random.default_rng(6)
    t = np.concatenate([np.arange(1000), 5000 + np.arange(1500)]) / RATE_HZ  # a 10 s gap
    x = rng.normal(0.0, 1.0, (len(t), 3))
    sp = vib.spectrum(vib.ImuTable("t", "gyro", t, x))
    _, first = vib.segment_psd(x[:1000], RATE_HZ, sp.nperseg)
    _, second = vib.segment_psd(x[1000:], RATE_HZ, sp.nperseg)
    expected = np.concatenate([first, second]).mean(axis=0)
    assert sp.segments == len(first) + len(second)
    np.testing.assert_allclose(sp.psd["y"], expected[:, 1], rtol=1e-12)


def test_too_few_samples_is_said():
    t = np.arange(20) / RATE_HZ
    with pytest.raises(vib.VibrationError, match="too few samples"):
        vib.spectrum(vib.ImuTable("t", "gyro", t, np.zeros((20, 3))))


def test_aliases_fold_into_the_first_nyquist_zone():
    assert vib.alias_hz(60.0, 100.0) == pytest.approx(40.0)
    assert vib.alias_hz(130.0, 100.0) == pytest.approx(30.0)
    assert vib.alias_hz(20.0, 100.0) == pytest.approx(20.0)


def _session(t, gyr_rad_s, acc_g):
    """The least a session offers the vibration view: its tables and the catalogue describing them."""
    from types import SimpleNamespace

    from groundstation.session_parts.catalogue import Catalogue, session_catalogue

    columns = {"time_s": t, **{f"gyr_{a}_rad_s": gyr_rad_s[:, i] for i, a in enumerate("xyz")},
               **{f"acc_{a}_g": acc_g[:, i] for i, a in enumerate("xyz")}}
    return SimpleNamespace(tables={"imu": columns}, catalogue=Catalogue({"imu": session_catalogue({})["imu"]}))


def test_a_log_too_slow_for_the_band_has_no_level_rather_than_zero():
    t = np.arange(400) / 4.0  # 4 Hz: Nyquist below the 5 Hz cut-off
    rng = np.random.default_rng(9)
    summary = vib.vibration_summary(_session(t, rng.normal(0, 0.1, (400, 3)), 1 + rng.normal(0, 0.01, (400, 3))))
    assert summary.levels["gyro"] == {"x": None, "y": None, "z": None}
    assert "level gyro (RMS above 5 Hz): none (sampled at 4.0 Hz" in "\n".join(summary.lines())
    assert summary.notch == {} and summary.peaks == []


def test_jittered_sample_times_are_one_stretch_but_a_real_gap_cuts():
    rng = np.random.default_rng(10)
    steps = 0.005 * (1 + rng.uniform(-0.5, 0.5, 999))  # a SITL log's 200 Hz, ±50 % jitter
    t = np.concatenate([[0.0], np.cumsum(steps)])
    assert vib.stretches(t) == [slice(0, 1000)]
    t[500:] += 0.02  # four periods missing
    assert vib.stretches(t) == [slice(0, 500), slice(500, 1000)]


def test_a_range_that_starts_a_hair_before_zero_reads_from_0_00_s():
    """A full-rate IMU's first sample 0.4 ms before the session's zero: the text said "from -0.00 s"."""
    t = np.arange(800) / RATE_HZ - 0.0004
    rng = np.random.default_rng(11)
    summary = vib.vibration_summary(_session(t, rng.normal(0, 0.1, (800, 3)), 1 + rng.normal(0, 0.01, (800, 3))))
    assert summary.start_s < 0
    assert summary.lines()[0] == f"vibration from 0.00 s to {t[-1]:.2f} s"

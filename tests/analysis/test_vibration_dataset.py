"""The vibration view of a BROAD trial with real vibration (27: a phone's vibration motor on the IMU),
against scipy.signal.welch on the CSV's own columns read here with numpy."""

import gzip

import numpy as np
import pytest
from scipy.signal import welch

from groundstation.analysis.vibration import MIN_ROTOR_HZ, vibration_summary
from groundstation.session_makers.load import load_session

from tests.shared_datasets import shared_dataset


def test_the_phone_motor_is_found_where_scipy_puts_it():
    trial = shared_dataset("broad/27_disturbed_phone_vibration_B.csv.gz")
    with gzip.open(trial, "rt") as f:
        header = f.readline().strip().split(",")
        table = np.loadtxt(f, delimiter=",", usecols=range(7))
    t, acc = table[:, 0], table[:, header.index("acc_x_m_s2") : header.index("acc_x_m_s2") + 3]
    summary = vibration_summary(load_session(trial))
    sp = summary.spectra["accel"]
    assert sp.table == "imu" and sp.rate_hz == pytest.approx(1.0 / np.median(np.diff(t)), rel=1e-6)
    f_ref, p_ref = welch(acc[:, 0], sp.rate_hz, window="hann", nperseg=sp.nperseg)  # the trial has no gaps
    np.testing.assert_allclose(sp.psd["x"], p_ref, rtol=1e-6)  # the loader's g round trip: float rounding
    band = f_ref >= MIN_ROTOR_HZ
    strongest = f_ref[band][np.argmax(p_ref[band])]
    top = max((p for p in summary.peaks if p.sensor == "accel"), key=lambda p: p.amplitude)
    assert top.frequency_hz == pytest.approx(strongest, abs=f_ref[1])
    assert summary.notch["frequency_hz"] == pytest.approx(strongest, abs=2 * f_ref[1])
    assert not any(p.label for p in summary.peaks)  # one motor without its 2× harmonic: no rotor family claimed

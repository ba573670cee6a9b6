"""The what-if filters against scipy.signal (lfilter, butter, freqz), and the difference they make on the simulator."""

import numpy as np
import pytest
from scipy.signal import butter, freqz, lfilter, lfilter_zi

from groundstation import cli
from groundstation.analysis import whatif
from groundstation.analysis.vibration import VibrationError
from groundstation.session_makers.load import load_session

RATE_HZ = 100.0


def test_the_causal_run_equals_scipys_lfilter_from_a_held_first_value():
    rng = np.random.default_rng(8)
    x = 1.0 + rng.normal(0.0, 0.3, (3000, 3))
    b, a = whatif.biquad("notch", 30.0, RATE_HZ, 15.0)
    expected = np.column_stack([lfilter(b, a, x[:, j], zi=lfilter_zi(b, a) * x[0, j])[0] for j in range(3)])
    np.testing.assert_allclose(whatif.apply(b, a, x), expected, rtol=1e-10, atol=1e-12)


def test_the_low_pass_is_scipys_butterworth():
    b, a = whatif.biquad("lowpass", 12.0, RATE_HZ)
    b_ref, a_ref = butter(2, 12.0, fs=RATE_HZ)
    np.testing.assert_allclose(b, b_ref, rtol=1e-10)
    np.testing.assert_allclose(a, a_ref, rtol=1e-10)


def test_the_notch_removes_its_centre_and_passes_the_rest():
    b, a = whatif.biquad("notch", 30.0, RATE_HZ, 10.0)
    f, h = freqz(b, a, worN=[0.0, 30.0, 49.99, 5.0], fs=RATE_HZ)
    gain = np.abs(h)
    assert gain[1] < 1e-9
    assert gain[0] == pytest.approx(1.0) and gain[2] == pytest.approx(1.0, abs=1e-3) and gain[3] > 0.98


@pytest.mark.parametrize(("kind", "hz"), [("notch", 60.0), ("lowpass", 0.0), ("bandstop", 10.0)])
def test_a_filter_that_does_not_fit_is_refused(kind, hz):
    with pytest.raises(VibrationError):
        whatif.biquad(kind, hz, RATE_HZ)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("whatif")
    for name, extra in (("shake", ["--vibration", "30"]), ("calm", [])):
        assert cli.main(["simulate", "--scenario", "static", "--duration", "30", "--seed", "4", *extra,
                         "--out", str(tmp / f"{name}.gsrec")]) == 0
    return tmp


def test_a_notch_on_the_motor_frequency_changes_a_shaken_attitude_not_a_calm_one(recordings):
    shaken = whatif.what_if(load_session(recordings / "shake.gsrec"), "notch", 30.0, 15.0, start_s=5.0)
    calm = whatif.what_if(load_session(recordings / "calm.gsrec"), "notch", 30.0, 15.0, start_s=5.0)
    assert shaken.attitude["estimator"] == "ahf2" and shaken.attitude["rows"] > 2000 and shaken.attitude_note is None
    assert shaken.attitude["rms_deg"] <= shaken.attitude["max_deg"]
    assert calm.attitude["rms_deg"] < 0.1 * shaken.attitude["rms_deg"]
    # the 30 Hz shake is what the notch removes from the spectrum, by tens of dB; the calm one has no peak to lose
    assert shaken.spectra["accel"].peak_hz == pytest.approx(30.0, abs=1.0) and shaken.spectra["accel"].attenuation_db < -20.0
    # AHF (seed 000's) takes the shaken accelerometer for attitude: the notch keeps it level by degrees
    ahf = whatif.what_if(load_session(recordings / "shake.gsrec"), "notch", 30.0, 15.0, start_s=5.0, estimator="ahf")
    assert ahf.attitude["estimator"] == "ahf" and ahf.attitude["rms_deg"] > 1.0


def test_a_filter_above_the_datas_nyquist_is_refused_not_folded(recordings):
    """A 130 Hz rotor on a 100 Hz IMU shows at 30 Hz; a filter placed by folding would act on an alias."""
    with pytest.raises(VibrationError, match="needs IMU data sampled faster than 260 Hz"):
        whatif.what_if(load_session(recordings / "shake.gsrec"), "notch", 130.0, 15.0)

"""The Vibration tab in the real window: a simulated vibrating recording opened, played to its end, and
the tab's spectrum, peaks, spectrogram and notch text are the vibration view's."""

import numpy as np
import pytest

from groundstation.cli import main

from tests.ui.helpers import open_file, play_to_the_end
from tests.waiting import LIMIT_MS

MOTOR_HZ = 24.0


@pytest.fixture(scope="module")
def shaken(tmp_path_factory):
    path = tmp_path_factory.mktemp("vib_ui") / "shake.gsrec"
    assert main(["simulate", "--scenario", "static", "--duration", "15", "--vibration", str(MOTOR_HZ), "--out", str(path)]) == 0
    return path


def test_the_vibration_tab_finds_the_motor_peak(window, qtbot, shaken):
    open_file(window, qtbot, shaken)
    play_to_the_end(window, qtbot)
    view = window.live_view
    tab = view.vibration
    view.tabs.setCurrentWidget(tab)  # computes when first shown
    qtbot.waitUntil(lambda: tab.summary is not None, timeout=LIMIT_MS)
    assert not tab.banner.isVisible()
    tab.sensor_box.setCurrentText("accel")
    peak = max((p for p in tab.summary.peaks if p.sensor == "accel"), key=lambda p: p.amplitude)
    assert peak.frequency_hz == pytest.approx(MOTOR_HZ, abs=2.0) and peak.label == "motor 1×"
    x, y = tab.peak_marks.getData()
    assert np.any(np.abs(x - peak.frequency_hz) < 1e-9)  # marked on the plot
    assert any(f"{peak.frequency_hz:.1f} Hz" in t.textItem.toPlainText() for t in tab.peak_texts)
    curves = [c for c in tab.spectrum_plot.getPlotItem().listDataItems() if c is not tab.peak_marks]
    assert len(curves) == 3
    np.testing.assert_allclose(curves[2].yData, tab.summary.spectra["accel"].amplitude["z"])
    assert tab.image.image.shape == tab.summary.spectra["accel"].spectrogram_psd.T.shape
    assert "INS_HNTCH_FREQ=24" in tab.text.toPlainText()


def test_a_range_too_short_is_said_in_the_tab(window, qtbot, shaken):
    open_file(window, qtbot, shaken)
    play_to_the_end(window, qtbot)
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)
    tab.whole.setChecked(False)
    tab.start_box.setValue(5.0)
    tab.end_box.setValue(5.1)
    tab.compute_button.click()
    assert tab.banner.isVisible() and "too few samples" in tab.banner.text()
    assert tab.summary is None and not tab.text.toPlainText()


def test_the_tab_says_what_the_suggested_notch_would_do_and_refuses_one_above_nyquist(window, qtbot, shaken):
    """The what-if row starts at the suggested notch; "Filter" shows the spectrum before and after, the gain and
    phase (``analysis.whatif``'s, for the same session and filter) and the text; a notch above the IMU's
    Nyquist is refused in the banner, never folded."""
    from groundstation.analysis.whatif import what_if

    open_file(window, qtbot, shaken)
    play_to_the_end(window, qtbot)
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.summary is not None, timeout=5000)
    assert tab.filter_box.currentText() == "notch" and tab.filter_hz.value() == pytest.approx(tab.summary.notch["frequency_hz"])
    tab.sensor_box.setCurrentText("accel")
    tab.filter_button.click()
    assert tab.change is not None and tab.what_if_plots.isVisible() and not tab.banner.isVisible()
    expected = what_if(window.session.data, "notch", tab.summary.notch["frequency_hz"], tab.summary.notch["bandwidth_hz"],
                       tab.summary.start_s, tab.summary.end_s)
    before, after = tab.before_after_plot.getPlotItem().listDataItems()
    np.testing.assert_allclose(after.yData, expected.spectra["accel"].after.total_psd[1:])
    np.testing.assert_allclose(before.yData, expected.spectra["accel"].before.total_psd[1:])
    (phase,) = tab.phase_plot.getPlotItem().listDataItems()
    np.testing.assert_allclose(phase.yData, expected.phase_deg)
    assert "\n".join(line for line in expected.lines()) in tab.text.toPlainText()
    assert expected.attitude is not None and "attitude (ahf2" in tab.text.toPlainText()
    tab.filter_hz.setValue(130.0)  # the 100 Hz IMU's Nyquist is 50 Hz
    tab.filter_button.click()
    assert tab.banner.isVisible() and "faster than 260 Hz" in tab.banner.text()
    assert tab.change is None and not tab.what_if_plots.isVisible()

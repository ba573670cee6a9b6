"""The Vibration tab in the real window: a simulated vibrating recording opened, played to its end, and
the tab's spectrum, peaks, spectrogram and notch text are the vibration view's."""

from pathlib import Path

import numpy as np
import pytest
from PySide6 import QtWidgets

from groundstation.cli import main
from groundstation.ui.vibration_view import NO_FREQUENCY

from tests.ui.helpers import open_file, play_to_the_end
from tests.waiting import LIMIT_MS

FLIGHTLOGS = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "flightlogs"


def shared_log(name: str) -> Path:
    """The shared flight log ``name``, or skip with the reason (the datasets are not part of the checkout)."""
    path = FLIGHTLOGS / name
    if not path.exists():
        pytest.skip(f"{path} is absent (the shared flight logs, ../shared/datasets/flightlogs)")
    return path

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
    assert np.any(np.abs(10.0 ** x - peak.frequency_hz) < 1e-9)  # marked on the plot (at log10(Hz), as the axis)
    assert any(f"{peak.frequency_hz:.1f} Hz" in t.textItem.toPlainText() for t in tab.peak_texts)
    curves = [c for c in tab.spectrum_plot.getPlotItem().listDataItems() if c is not tab.peak_marks]
    assert len(curves) == 3
    np.testing.assert_allclose(curves[2].yData, 20.0 * np.log10(tab.summary.spectra["accel"].amplitude["z"][1:]))
    # the spectrogram on the spectrum's log-frequency axis (issue 34: it was linear): its rows at log10(Hz), the
    # motor's row the brightest, the axis labelled at each decade
    sp = tab.summary.spectra["accel"]
    rows, columns = tab.image.image.shape
    assert columns == len(sp.spectrogram_t_s)
    rect = tab.image.mapRectToView(tab.image.boundingRect())
    assert rect.top() == pytest.approx(np.log10(sp.frequency_hz[1]), abs=0.05)
    assert rect.bottom() == pytest.approx(np.log10(sp.frequency_hz[-1]), abs=0.05)
    brightest = int(np.argmax(tab.image.image.mean(axis=1)))
    row_hz = 10.0 ** (rect.top() + (brightest + 0.5) * rect.height() / rows)
    assert row_hz == pytest.approx(peak.frequency_hz, abs=2 * (sp.frequency_hz[1] - sp.frequency_hz[0]))
    ticks = tab.spectrogram_plot.getAxis("left")._tickLevels[0]
    assert [label for _, label in ticks][:4] == ["0.1", "1", "10", "100"]
    assert "INS_HNTCH_FREQ=24" in tab.text.toPlainText()


def test_a_range_too_short_is_said_in_the_tab(window, qtbot, shaken):
    open_file(window, qtbot, shaken)
    play_to_the_end(window, qtbot)
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)
    tab.whole.setChecked(False)
    tab.start_box.setValue(5.0)
    tab.end_box.setValue(5.1)
    before = tab.spectrum_plot.geometry()
    tab.compute_button.click()
    assert tab.banner.isVisible() and "too few samples" in tab.banner.text()
    assert tab.summary is None and not tab.text.toPlainText()
    QtWidgets.QApplication.processEvents()  # a layout would move the plots now
    assert tab.spectrum_plot.geometry() == before  # the banner lies over the plots' top: nothing jumps (issue 34)
    assert tab.banner.mapTo(tab, tab.banner.rect().topLeft()).y() == tab.spectrum_plot.y()  # on the spectrum


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


def test_the_what_if_row_starts_empty_on_a_file_with_no_notch_to_suggest(window, qtbot, shaken, tmp_path):
    """The next file's tab showed the last file's notch (54.2 Hz of an ArduCopter log over a PX4 log that has none)."""
    tab = shown_tab(window, qtbot, shaken, "gyro")
    assert tab.filter_hz.value() == pytest.approx(tab.summary.notch["frequency_hz"])
    still = tmp_path / "still.gsrec"
    assert main(["simulate", "--scenario", "static", "--duration", "15", "--out", str(still)]) == 0
    tab = shown_tab(window, qtbot, still, "gyro")
    assert tab.summary.notch == {}
    assert tab.filter_hz.value() == 0.0 and tab.filter_bw.value() == 0.0
    check_no_filter_yet(tab)


def check_no_filter_yet(tab):
    """No "0.0 Hz" to filter at: the box says a frequency is to be set, and Filter waits for one."""
    assert tab.filter_hz.text() == NO_FREQUENCY and "Hz" not in tab.filter_hz.text()
    assert not tab.filter_button.isEnabled() and "frequency" in tab.filter_button.toolTip()
    tab.filter_hz.setValue(30.0)
    assert tab.filter_button.isEnabled()
    tab.filter_hz.setValue(0.0)
    assert not tab.filter_button.isEnabled()


def test_the_what_if_row_of_a_live_session_with_no_notch_to_suggest_waits_for_a_frequency(window, qtbot):
    """Issue 34, the tour's defect 5: live, with no notch suggested, the row read "0.0 Hz" and Filter only said an error."""
    window.connect_serial("sim:?seed=8")
    qtbot.waitUntil(lambda: window.session is not None and len(window.session.view.imu) > 600, timeout=LIMIT_MS)
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.summary is not None, timeout=LIMIT_MS)
    assert tab.summary.notch == {}
    check_no_filter_yet(tab)


def shown_tab(window, qtbot, path, sensor):
    """The Vibration tab of ``path`` played to its end, computed and showing ``sensor``."""
    open_file(window, qtbot, path)
    play_to_the_end(window, qtbot)
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)  # computes when first shown
    qtbot.waitUntil(lambda: tab.summary is not None, timeout=LIMIT_MS)
    tab.sensor_box.setCurrentText(sensor)
    return tab


def overlapping(labels) -> bool:
    """Whether any two of the labels' boxes on screen (scene coordinates) overlap."""
    boxes = [t.sceneBoundingRect() for t in labels]
    return any(a.intersects(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])


def test_the_spectrum_is_in_db_on_a_log_frequency_axis(window, qtbot, shaken):
    """x in log mode without the zero-frequency bin; y is 20·log10 of the analysis's amplitude (dB re 1 unit)."""
    tab = shown_tab(window, qtbot, shaken, "gyro")
    plot = tab.spectrum_plot.getPlotItem()
    assert plot.getAxis("bottom").logMode and not plot.getAxis("left").logMode
    major = dict(plot.getAxis("bottom")._tickLevels[0])  # the ticks set (pyqtgraph keeps them there): 1, 2, 5 a decade
    shown = {text for value, text in major.items() if 0.0 <= value <= 3.0 + 1e-9}  # 1 Hz to 1 kHz
    assert shown == {"1", "2", "5", "10", "20", "50", "100", "200", "500", "1000"}
    sp = tab.summary.spectra["gyro"]
    assert sp.frequency_hz[0] == 0.0
    curves = [c for c in plot.listDataItems() if c is not tab.peak_marks]
    assert [c.name() for c in curves] == ["x", "y", "z"]
    for curve in curves:
        amplitude = sp.amplitude[curve.name()][1:]
        assert np.all(amplitude > 0)  # none drawn at the floor: each value is its own dB
        np.testing.assert_allclose(curve.xData, sp.frequency_hz[1:])
        np.testing.assert_allclose(curve.yData, 20.0 * np.log10(amplitude), rtol=1e-12)
    assert f"dB re 1 {sp.unit}" in plot.getAxis("left").labelText + plot.getAxis("left").labelUnits
    peaks = [p for p in tab.summary.peaks if p.sensor == "gyro"]
    x, _ = tab.peak_marks.getData()
    np.testing.assert_allclose(10.0 ** x, [p.frequency_hz for p in peaks])  # markers sit at log10(Hz), as the axis


def test_labels_of_many_close_peaks_do_not_overlap(window, qtbot):
    """PX4's bench sample: ten gyro peaks between 4 and 30 Hz. Every peak is marked, at most five labelled,
    the strongest always, and no two labels shown overlap on screen, nor once zoomed in (where more fit); the
    text still lists every peak."""
    path = shared_log("px4_auavx21_bench_sample.ulg")
    tab = shown_tab(window, qtbot, path, "gyro")
    peaks = [p for p in tab.summary.peaks if p.sensor == "gyro"]
    assert len(peaks) >= 8
    x, _ = tab.peak_marks.getData()
    assert len(x) == len(peaks)
    tab.spectrum_plot.grab()  # painted: every item's transform is the one on screen
    shown = [t for t in tab.peak_texts if t.isVisible()]
    strongest = max(peaks, key=lambda p: p.amplitude)
    assert 1 <= len(shown) <= 5 and shown[0].toPlainText().startswith(f"{strongest.frequency_hz:.1f} Hz")
    assert not overlapping(shown)
    tab.spectrum_plot.setXRange(np.log10(4.0), np.log10(14.0), padding=0)  # zoomed in: room for more labels
    tab.spectrum_plot.grab()
    zoomed = [t for t in tab.peak_texts if t.isVisible()]
    assert len(zoomed) > len(shown) and not overlapping(zoomed)
    text = tab.text.toPlainText()
    assert all(f"{p.frequency_hz:>14.2f}" in text for p in peaks)


def test_all_data_of_a_file_is_the_whole_file_not_the_part_played(window, qtbot):
    """Issue 34: "All data" was the part played so far (a spectrum of 0.14 s after a log was reopened)."""
    path = shared_log("px4_auavx21_bench_sample.ulg")
    open_file(window, qtbot, path)
    window.seek(0.5)  # the clock near its start (a flight log opens paused, whole)
    played_s = window.session.source.position_s
    view = window.live_view
    tab = view.vibration
    view.tabs.setCurrentWidget(tab)
    qtbot.waitUntil(lambda: tab.summary is not None or tab.banner.isVisible(), timeout=LIMIT_MS)
    assert tab.summary is not None, tab.banner.text()
    whole = window.session.data.time_s
    assert tab.summary.end_s - tab.summary.start_s > 0.9 * (whole[-1] - whole[0]) > 10 * max(played_s, 1.0)


def test_a_live_sessions_tab_reads_its_product_so_far(window, qtbot):
    """A live session (the simulated bridge, vibrating): the tab's data is the session's product of the rows so
    far (``SessionData``, built as a file's is), and finds the motor peak in them."""
    from groundstation.session.product import SessionData

    window.connect_serial(f"sim:?scenario=static&vibration={MOTOR_HZ:g}&seed=5")
    assert window.session is not None and not window.session.seekable
    qtbot.waitUntil(lambda: len(window.session.view.imu) >= 600, timeout=LIMIT_MS)  # 6 s at 100 Hz
    tab = window.live_view.vibration
    window.live_view.tabs.setCurrentWidget(tab)  # computes when first shown
    qtbot.waitUntil(lambda: tab.summary is not None, timeout=LIMIT_MS)
    snapshot = tab._snapshot()
    assert isinstance(snapshot, SessionData) and len(snapshot) >= 600
    peak = max((p for p in tab.summary.peaks if p.sensor == "accel"), key=lambda p: p.amplitude)
    assert peak.frequency_hz == pytest.approx(MOTOR_HZ, abs=2.0)
    window.disconnect()

"""A flight log opens on the whole flight (issue 34): computed whole, it is shown whole at once (the clock
at its end, paused; the time window the whole session), not played at 1x into a 30 s window. Playback is a
click away; the legend's names toggle curves; the paper's AHF starts switched off."""

from pyqtgraph.Qt import QtTest
from PySide6 import QtCore

from groundstation.estimation import label
from tests.ui.helpers import open_file
from tests.ui.test_replay import flightlog, points
from tests.waiting import LIMIT_MS

HOP = "px4_fmuv5_quad_hop.ulg"


def test_a_flight_log_opens_on_the_whole_flight_with_playback_at_hand(window, qtbot, recording):
    open_file(window, qtbot, flightlog(HOP))
    assert window.banner.isHidden(), window.banner.text()
    session, live = window.session, window.live_view
    rows = len(session.data.tables["imu"]["time_s"])
    assert session.source.paused and session.source.position_s == session.source.duration_s
    assert live.window_box.currentText() == "whole session"
    ahf2 = next(c for s, c in live.attitude.curves if s.label == label("ahf2") and s.quantity.endswith("pitch_deg"))
    qtbot.waitUntil(lambda: points(ahf2) == rows, timeout=LIMIT_MS)  # every row, with no seek and no wait for a clock
    low, high = live.attitude.items[0].getViewBox().viewRange()[0]
    t = session.data.tables["imu"]["time_s"]
    assert low <= t[0] + 0.5 and high >= t[-1] - 0.5
    # playback is still there: from the start, it reveals again
    window.seek(0.0)
    window.replay_bar.play_button.click()
    qtbot.waitUntil(lambda: not session.source.paused, timeout=LIMIT_MS)
    # the paper's AHF starts hidden; a click on a legend name toggles its curves
    ahf = next(c for s, c in live.attitude.curves if s.label == label("ahf"))
    assert not ahf.isVisible()
    plots = live.attitude
    _, text = next((s, t) for s, t in plots.legend.items if t.text == label("ahf2"))
    centre = plots.mapFromScene(text.mapToScene(text.boundingRect().center()))
    QtTest.QTest.mouseClick(plots.viewport(), QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, centre)
    qtbot.waitUntil(lambda: not ahf2.isVisible(), timeout=LIMIT_MS)
    # a recording (not a flight log) still plays from its start in the window the user chose
    live.window_box.setCurrentText("30 s")
    open_file(window, qtbot, recording)
    assert not window.session.source.paused and window.session.source.position_s < window.session.source.duration_s
    assert live.window_box.currentText() == "30 s"

"""Issue 34, the tour's defects 1 and 2: where the IMU is too slow for the host estimators
(``autopilot.imu_rate.MIN_FILTER_RATE_HZ``, as the attitude panel decides it), the aircraft's own estimate is the
main attitude curve and the host estimators start switched off (the user may tick them), and the Position tab
shows the GPS track, not a fused position integrated from that IMU, and says why."""

from PySide6 import QtCore

from tests.ui.test_first_session import type_in_source_box
from tests.waiting import LIMIT_MS


def test_a_5_hz_imu_draws_the_onboard_attitude_and_the_gps_track_and_no_fused_position(window, qtbot):
    type_in_source_box(qtbot, window, "sim:?rate=5&sensors=gps&seed=8")
    qtbot.keyClick(window.bar.port_box.lineEdit(), QtCore.Qt.Key_Return)
    session, view = window.session, window.live_view
    qtbot.waitUntil(lambda: len(session.view.imu) > 8 and len(session.view.tables.get("position") or ()) > 8
                    and window.attitude_panel.title() == "Attitude (onboard — IMU at 5.0 Hz)", timeout=LIMIT_MS)
    qtbot.waitUntil(lambda: view.attitude.curves[0][0].label == "onboard", timeout=LIMIT_MS)
    main, _ = view.attitude.curves[0]
    assert not main.reference  # solid, over the others
    ahf2 = next(c for s, c in view.attitude.curves if s.label == "AHF2")
    assert not ahf2.isVisible()
    ahf2.setVisible(True)  # a click on its legend entry: the user may still look at it
    roll_ahf2 = next(c for s, c in view.attitude.curves if s.label == "AHF2" and s.quantity == "ahf2_roll_deg")
    assert roll_ahf2.isVisible()

    view.tabs.setCurrentWidget(view.position)
    position = view.position
    qtbot.waitUntil(lambda: position.tracks["gps"].xData is not None and len(position.tracks["gps"].xData) > 3, timeout=LIMIT_MS)
    assert position.tracks["position"].xData is None or not len(position.tracks["position"].xData)
    fused_height = next(c for s, c in position.height.curves if s.series == "position")
    assert fused_height.xData is None or not len(fused_height.xData)
    assert position.fused_note.isVisible() and "5.0 Hz" in position.fused_note.text()

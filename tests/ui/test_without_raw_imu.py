"""Issue 24, defects 3 and 5: without raw IMU (the firmware's "estimated" mode) or with an IMU too slow
for host filtering (an autopilot's RAW_IMU at 4.0 Hz), the aircraft's own estimate carries the view and
the attitude panel, and says so; back in "both", the stretch without raw IMU is no gap and no host curve
draws a line across it."""

import numpy as np
from PySide6 import QtCore
import pyqtgraph as pg

from tests.ui.test_first_session import click_tab
from tests.ui.test_mavlink_heard import sitl_on_udp  # noqa: F401 (a fixture)
from tests.ui.test_first_session import type_in_source_box
from tests.waiting import LIMIT_MS


def set_mode(qtbot, window, mode: str) -> None:
    """Uplink tab, the mode box, Set mode, then wait for the aircraft's ACK."""
    click_tab(qtbot, window.controls, window.controls.indexOf(window.uplink_panel))
    window.uplink_panel.mode_box.setCurrentText(mode)
    qtbot.mouseClick(window.uplink_panel.mode_button, QtCore.Qt.LeftButton)
    qtbot.waitUntil(lambda: "ACK ok" in window.uplink_panel.answers.text().split("\n")[0], timeout=LIMIT_MS)


def right_edge_s(window) -> float:
    return window.live_view.attitude.items[0].getViewBox().viewRange()[0][1]


def badge_over(qtbot, window, seconds: float) -> set[str]:
    """Every text the link badge showed over ``seconds``, read as the window shows it (5 times a second)."""
    headlines = set()
    for _ in range(int(seconds * 5)):
        qtbot.wait(200)
        headlines.add(window.link_panel.headline.text())
    return headlines


def test_estimated_mode_keeps_the_view_moving_on_the_onboard_estimate(window, qtbot):
    window.start_demo()
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 200 and window.live_view.frames_drawn > 10, timeout=LIMIT_MS)
    assert window.attitude_panel.title() == "Attitude (AHF2)"
    set_mode(qtbot, window, "estimated")
    switched_s = float(session.view.imu.tail(1)[0][0])
    qtbot.waitUntil(lambda: len(session.view.onboard) and session.view.onboard.tail(1)[0][0] > switched_s + 5, timeout=LIMIT_MS)  # past one step of the axis (4 s)
    onboard_s = float(session.view.onboard.tail(1)[0][0])
    qtbot.waitUntil(lambda: right_edge_s(window) >= onboard_s, timeout=LIMIT_MS)  # the time axis follows the aircraft's estimate
    assert window.attitude_panel.title() == "Attitude (onboard — no raw IMU)"
    onboard = window.live_view.series["onboard"]
    pitch = float(onboard.recent.values["onboard_pitch_deg"][onboard.recent.count - 1])
    assert window.attitude_panel.readouts["pitch"].text() != "—"
    assert abs(float(window.attitude_panel.readouts["pitch"].text().rstrip("°")) - pitch) < 2.0  # moving with it
    set_mode(qtbot, window, "both")
    qtbot.waitUntil(lambda: session.view.imu.tail(1)[0][0] > onboard_s + 1, timeout=LIMIT_MS)
    qtbot.waitUntil(lambda: window.attitude_panel.title() == "Attitude (AHF2)", timeout=LIMIT_MS)
    plots = window.live_view.attitude
    shaded = [r.getRegion() for r in plots.items[0].items if isinstance(r, pg.LinearRegionItem)]
    assert not any(low < onboard_s < high for low, high in shaded)  # the onboard estimate never stopped
    ahf2 = next(c for s, c in plots.curves if s.quantity == "ahf2_pitch_deg")
    t, values = plots.drawn(ahf2)
    inside = (t > switched_s + 0.5) & (t < onboard_s)
    assert inside.any() and np.isnan(values[inside]).all()  # broken across the stretch, no straight line


def test_a_4_hz_autopilot_shows_its_own_estimate_as_the_attitude_and_its_link_stays_ok(window, qtbot, sitl_on_udp):  # noqa: F811
    """SITL's default stream rates (RAW_IMU and ATTITUDE at 4 Hz), the request for more answered by
    asking for 4 Hz again on the Uplink tab: the host estimates mean little, the badge stays LINK OK."""
    type_in_source_box(qtbot, window, f"mavlink:udpin:127.0.0.1:{sitl_on_udp}")
    qtbot.keyClick(window.bar.port_box.lineEdit(), QtCore.Qt.Key_Return)
    click_tab(qtbot, window.controls, window.controls.indexOf(window.uplink_panel))
    window.uplink_panel.stream_rate_hz.setValue(4)
    qtbot.mouseClick(window.uplink_panel.streams_button, QtCore.Qt.LeftButton)
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 30, timeout=LIMIT_MS)
    headlines = badge_over(qtbot, window, 8.0)
    assert window.attitude_panel.title().startswith("Attitude (onboard — IMU at 4.0 Hz")
    assert headlines == {"LINK OK"}


def test_a_healthy_4_hz_bridge_keeps_its_badge_ok_and_shows_the_onboard_attitude(window, qtbot):
    """The project's bridge at 4 Hz (a slow radio's setting): a frame every 250 ms is its healthy pace."""
    type_in_source_box(qtbot, window, "sim:?rate=4&sensors=&seed=8")
    qtbot.keyClick(window.bar.port_box.lineEdit(), QtCore.Qt.Key_Return)
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 8, timeout=LIMIT_MS)
    assert badge_over(qtbot, window, 6.0) == {"LINK OK"}
    assert window.attitude_panel.title() == "Attitude (onboard — IMU at 4.0 Hz)"

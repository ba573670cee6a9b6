"""The window on a live MAVLink link (real UDP on localhost, offscreen Qt): the Uplink panel offers an
autopilot only stream-rate requests, and a request at another rate changes the rate the aircraft
sends; the link panel shows both radios' signal and the battery as the simulated aircraft reports them."""

import numpy as np
import pytest

from groundstation.sim.mavlink_aircraft import BATTERY, RADIO_STATUS
from tests.waiting import LIMIT_MS


def imu_period_us(window, last: int) -> float:
    with window.session.lock:
        times = window.session.view.imu.column("device_time_us")[-last:]
    return float(np.median(np.diff(times)))


def test_uplink_panel_requests_another_stream_rate_and_the_aircraft_follows(qtbot, mavlink_window):
    window = mavlink_window
    panel = window.uplink_panel
    assert panel.isEnabled()
    assert panel.mavlink_controls.isVisibleTo(panel) and not panel.gs_controls.isVisibleTo(panel)
    assert not window.estimator_panel.send_button.isEnabled()  # no AHF on an autopilot
    qtbot.waitUntil(lambda: len(window.session.view.imu) > 60, timeout=LIMIT_MS)
    assert imu_period_us(window, 20) == 20_000  # the session's own request: 50 Hz
    panel.stream_rate_hz.setValue(25)
    panel.streams_button.click()
    events = [e for e in window.session.view.events if e.get("command") == "request_streams"]
    assert events and events[-1]["rate_hz"] == 25
    count = len(window.session.view.imu)
    qtbot.waitUntil(lambda: len(window.session.view.imu) > count + 40, timeout=LIMIT_MS)
    assert imu_period_us(window, 20) == 40_000


def test_link_panel_shows_both_radios_signal_and_the_battery(qtbot, mavlink_window):
    window = mavlink_window
    values = window.link_panel.values
    qtbot.waitUntil(lambda: values["RSSI ground / air"].text() != "—", timeout=LIMIT_MS)
    assert values["RSSI ground / air"].text() == f"{RADIO_STATUS['rssi']} / {RADIO_STATUS['remrssi']}"
    assert values["noise ground / air"].text() == f"{RADIO_STATUS['noise']} / {RADIO_STATUS['remnoise']}"
    assert values["radio rx errors"].text() == str(RADIO_STATUS["rxerrors"])
    qtbot.waitUntil(lambda: values["battery"].text() != "—", timeout=LIMIT_MS)
    assert values["battery"].text() == (f"{BATTERY['voltage_battery'] / 1000:.2f} V, {BATTERY['current_battery'] / 100:.1f} A, "
                                        f"{BATTERY['battery_remaining']} % left")  # mV, cA, %
    assert window.link_panel.values["RSSI ground / air"].isVisibleTo(window.link_panel)
    window.disconnect()  # no figure of a stopped link stands
    qtbot.waitUntil(lambda: not window.link_panel.values["RSSI ground / air"].isVisibleTo(window.link_panel), timeout=LIMIT_MS)


def test_the_projects_own_link_shows_no_radio_rows_and_its_own_uplink(qtbot, tmp_path):
    from PySide6 import QtCore

    from groundstation.session_makers.factory import Sessions

    from groundstation.ui.main_window import MainWindow

    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(window)
    window.show()
    window.start_demo()
    qtbot.waitUntil(lambda: len(window.session.view.imu) > 50, timeout=LIMIT_MS)
    qtbot.wait(300)
    panel = window.uplink_panel
    assert panel.gs_controls.isVisibleTo(panel) and not panel.mavlink_controls.isVisibleTo(panel)
    assert not window.link_panel.values["RSSI ground / air"].isVisibleTo(window.link_panel)
    with pytest.raises(ValueError, match="MAVLink"):
        window.session.request_streams(25)

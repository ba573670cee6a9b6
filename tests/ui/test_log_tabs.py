"""A flight log in the real window (issue 23): the Heading and Position tabs filled from its GPS,
barometer and compass, the Channels list with a table per message type, a SITL log's truth dashed
beside the estimates, and File > "Full-rate IMU" reopening the log on its fast stream."""

import numpy as np
from PySide6 import QtCore

from tests.ui.helpers import open_file
from tests.ui.test_replay import flightlog, points
from tests.waiting import LIMIT_MS

COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"
SITL_ULOG = "px4_sitl_quad_groundtruth.ulg"


def played_to_the_end(window, qtbot, path):
    open_file(window, qtbot, path, timeout_ms=180000)
    assert window.banner.isHidden(), window.banner.text()
    assert not window.session.running and window.live_view.window_box.currentText() == "whole session"  # opened whole
    return window.live_view


def curve(plots, quantity):
    return next(c for spec, c in plots.curves if spec.quantity == quantity)


def test_a_dataflash_log_fills_the_heading_and_position_tabs_and_lists_its_tables(window, qtbot):
    live = played_to_the_end(window, qtbot, flightlog(COPTER))
    tabs = live.tabs
    qtbot.waitUntil(lambda: tabs.isTabVisible(tabs.indexOf(live.heading)) and tabs.isTabVisible(tabs.indexOf(live.position)),
                    timeout=LIMIT_MS)  # fmt: skip
    tabs.setCurrentWidget(live.heading)
    compass = curve(live.heading, "compass_heading_deg")
    qtbot.waitUntil(lambda: points(compass) >= len(window.session.data.tables["mag_raw"]["time_s"]), timeout=LIMIT_MS)
    assert np.isfinite(compass.yData).mean() > 0.99
    tabs.setCurrentWidget(live.position)
    qtbot.waitUntil(lambda: points(live.position.tracks["gps"]) > 400 and points(live.position.tracks["position"]) > 1000,
                    timeout=LIMIT_MS)  # fmt: skip
    tables = [live.channels.tree.topLevelItem(i).text(0) for i in range(live.channels.tree.topLevelItemCount())]
    assert {"imu", "gps", "mag_raw", "position", "att", "vibe_0", "gyro_fast_0", "accel_fast_0"} <= set(tables)
    assert len(tables) > 60
    imu = next(live.channels.tree.topLevelItem(i) for i in range(len(tables)) if tables[i] == "imu")
    assert "host arrival time (s)" not in [imu.child(k).text(0) for k in range(imu.childCount())]


def test_a_sitl_log_plots_its_truth_dashed(window, qtbot):
    live = played_to_the_end(window, qtbot, flightlog(SITL_ULOG))
    truth = curve(live.attitude, "truth_pitch_deg")
    live.pause_button.setChecked(True)  # a paused view draws every sample (a following one, each pixel column's)
    qtbot.waitUntil(lambda: points(truth) == len(window.session.data.tables["truth"]["time_s"]), timeout=LIMIT_MS)
    assert truth.opts["pen"].style() == QtCore.Qt.DashLine
    assert np.nanmax(np.abs(truth.yData)) > 1.0  # it flew


def test_the_file_menu_reopens_a_log_on_its_full_rate_imu_and_says_why_bursts_stay_off_the_estimators(window, qtbot):
    live = played_to_the_end(window, qtbot, flightlog(COPTER))
    before = window.session
    regular = len(before.data.tables["imu"]["time_s"])
    window.fast_imu_action.setChecked(True)
    qtbot.waitUntil(lambda: window.loading is None and window.session is not None and window.session is not before,
                    timeout=180000)  # fmt: skip
    assert window.sessions.imu == "fast" and window.banner.isHidden()
    # ArduPilot's batch sampler writes bursts: the estimators stay on the logged IMU, and the Events tab says why
    assert len(window.session.data.tables["imu"]["time_s"]) == regular
    console = window.event_console.table
    qtbot.waitUntil(lambda: any("bursts" in (console.item(r, 2).text() if console.item(r, 2) else "")
                                for r in range(console.rowCount())), timeout=10000)
    assert live.tabs.count() > 0
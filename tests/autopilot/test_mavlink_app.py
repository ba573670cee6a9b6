"""The app's window on a live MAVLink link (real UDP on localhost, offscreen Qt): the port box's
``mavlink:`` spec opens a session that the window shows and records like any other."""

import numpy as np

from tests.waiting import LIMIT_MS


def test_window_shows_and_records_a_mavlink_link(qtbot, mavlink_window):
    window = mavlink_window
    qtbot.waitUntil(lambda: len(window.session.view.imu) > 100, timeout=LIMIT_MS)  # the window ticks meanwhile
    qtbot.wait(300)
    session = window.session
    assert session.view.protocol == "mavlink" and session.error is None
    periods_us = np.diff(session.view.imu.to_dict()["device_time_us"])
    assert np.median(periods_us) == 20_000  # the session asked for 50 Hz
    assert session.recording_path is not None and session.recording_path.stat().st_size > 0
    assert not window.banner.isVisible(), window.banner.text()

"""The app's window on a live MAVLink link (real UDP on localhost, offscreen Qt): the port box's
``mavlink:`` spec opens a session that the window shows and records like any other."""

import socket
import threading

import numpy as np

from groundstation.sim.mavlink_aircraft import MavlinkAircraft
from groundstation.sim.udp_bridge import UdpBridge



def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_window_shows_and_records_a_mavlink_link(qtbot, tmp_path):
    from PySide6 import QtCore

    from groundstation.ui.main_window import MainWindow

    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(window)
    window.show()
    port = free_udp_port()
    window.connect_serial(f"mavlink:udpin:127.0.0.1:{port}", 115200)
    assert not window.banner.isVisible(), window.banner.text()
    bridge = UdpBridge(MavlinkAircraft(), ("127.0.0.1", port))
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop.is_set,), daemon=True)
    thread.start()
    try:
        qtbot.waitUntil(lambda: len(window.session.pipeline.imu) > 100, timeout=8000)  # the window ticks meanwhile
        qtbot.wait(300)
    finally:
        stop.set()
        thread.join()
        bridge.close()
    session = window.session
    assert session.pipeline.protocol == "mavlink" and session.error is None
    periods_us = np.diff(session.pipeline.imu.to_dict()["device_time_us"])
    assert np.median(periods_us) == 20_000  # the session asked for 50 Hz
    assert session.recording_path is not None and session.recording_path.stat().st_size > 0
    assert not window.banner.isVisible(), window.banner.text()

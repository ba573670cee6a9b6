"""Bad inputs and lost ports show a message in the window, never an exception."""

import errno
import os
import subprocess
import sys

import pyqtgraph as pg
import pytest

from groundstation.sources.serial_port import explain_port_error
from groundstation.ui.series import shared_gaps

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_missing_or_damaged_recording_shows_a_message(window, qtbot, tmp_path):
    open_file(window, qtbot, tmp_path / "missing.gsrec")
    assert window.banner.isVisible() and "no such file" in window.banner.text()
    damaged = tmp_path / "damaged.gsrec"
    damaged.write_bytes(b"this is not a recording at all" * 10)
    open_file(window, qtbot, damaged)
    assert window.banner.isVisible() and "damaged.gsrec" in window.banner.text()
    assert window.session is None


def test_a_port_that_cannot_be_opened_shows_why(window):
    window.connect_serial("/dev/no-such-serial-port", 115200)
    assert window.banner.isVisible() and "/dev/no-such-serial-port" in window.banner.text()
    assert window.session is None
    reason = os.strerror(errno.ENOENT)  # the system's words, said once (pyserial repeats the OS error in its own)
    assert window.banner.text().count(reason) == 1 and window.banner.text().count("[Errno") == 1


@pytest.mark.skipif(os.name != "posix", reason="the simulated bridge's pseudo-terminal is POSIX")
def test_unplugged_port_is_shown_reopened_and_the_gap_marked(window, qtbot, tmp_path):
    link = tmp_path / "radio"
    bridge = subprocess.Popen(
        [sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "hover", "--dropout-every", "3",
         "--dropout-s", "1", "--link", str(link)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        bridge.stdout.readline()  # the pty is up
        window.connect_serial(str(link), 115200)
        session = window.session
        recording = session.recording_path
        qtbot.waitUntil(lambda: window.link_panel.headline.text().startswith("PORT GONE"), timeout=LIMIT_MS)
        qtbot.waitUntil(lambda: window.link_panel.headline.text() == "LINK OK", timeout=LIMIT_MS)
        qtbot.waitUntil(lambda: bool(window.live_view.series["imu"].gaps), timeout=LIMIT_MS)
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)
    start, end = window.live_view.series["imu"].gaps[0]
    assert 0.9 < end - start < 1.6  # the second the port was away
    shaded = [i for i in window.live_view.attitude.items[0].items if isinstance(i, pg.LinearRegionItem)]
    # Shaded: the time with neither raw IMU nor the aircraft's own estimate (their frames a sample apart).
    regions = [tuple(region.getRegion()) for region in shaded]
    assert regions == shared_gaps(window.live_view.series)
    assert regions[0] == pytest.approx((start, end), abs=0.02)
    assert window.session is session and session.recording_path == recording  # same session, same file
    assert window.banner.isHidden()


def test_port_errors_say_what_to_do():
    denied = explain_port_error("cannot open serial port /dev/ttyUSB0: [Errno 13] could not open port: Permission denied")
    busy = explain_port_error("cannot open serial port /dev/ttyUSB0: [Errno 16] Device or resource busy")
    if sys.platform.startswith("linux"):
        assert "dialout" in denied
    assert "in use by another program" in busy


def test_no_link_figure_stands_after_disconnect(window, qtbot):
    window.start_demo()
    qtbot.waitUntil(lambda: window.link_panel.values["frames/s"].text() not in ("—", "0"), timeout=LIMIT_MS)
    window.bar.disconnect_button.click()
    qtbot.waitUntil(lambda: window.link_panel.headline.text() == "no source"  # at the next figure refresh
                    and {label.text() for label in window.link_panel.values.values()} == {"—"}, timeout=LIMIT_MS)

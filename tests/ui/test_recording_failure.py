"""The window when the recordings' disk fills up during a live session (a real tmpfs, filled when the test says): a loud
banner says so and why, the plots go on, the status bar stops saying "recording", "Resume recording"
starts a new file once there is room, and closing the window raises nothing."""

import numpy as np
from PySide6 import QtCore

from tests.session.full_disk import fill, grow, tiny_tmpfs, use_up
from tests.waiting import LIMIT_MS


def newest_plotted_time(window) -> float:
    _, curve = window.live_view.attitude.curves[0]
    x, _ = curve.getData()
    return float(np.nanmax(x)) if x is not None and len(x) else float("nan")


def test_a_full_disk_shows_a_banner_the_plots_go_on_and_resume_starts_a_new_file(window, qtbot, tmp_path):
    with tiny_tmpfs(tmp_path / "full", size="1m", room_bytes=512_000) as folder:  # minutes of the demo's link bytes
        window.recordings_dir = folder
        window.start_demo()
        session = window.session
        session.recorder.retry_interval_s = None  # resuming is the user's action in this test
        first = session.recording_path
        qtbot.waitUntil(lambda: "● recording" in window.recording_label.text(), timeout=LIMIT_MS)
        assert not window.recording_banner.isVisible()
        use_up(folder, "filler2")  # the disk is full now, however slowly a loaded machine came this far

        qtbot.waitUntil(window.recording_banner.isVisible, timeout=LIMIT_MS)
        text = window.recording_banner.label.text()
        assert "RECORDING STOPPED" in text and "No space left on device" in text
        assert "Decoding and the display go on" in text and str(first) in text
        qtbot.waitUntil(lambda: "NOT RECORDING" in window.recording_label.text(), timeout=LIMIT_MS)
        assert "● recording" not in window.recording_label.text()

        # The plots go on: the newest plotted time advances while nothing is recorded.
        before = newest_plotted_time(window)
        qtbot.waitUntil(lambda: newest_plotted_time(window) > before + 1.0, timeout=LIMIT_MS)
        assert session.running

        # Resume while the disk is still full: it says why and leaves no file behind.
        qtbot.mouseClick(window.recording_banner.resume_button, QtCore.Qt.MouseButton.LeftButton)
        assert window.recording_banner.isVisible() and session.recorder.state == "failed"
        assert [p.name for p in folder.glob("*.gsrec")] == [first.name]

        grow(folder, "16m")
        qtbot.mouseClick(window.recording_banner.resume_button, QtCore.Qt.MouseButton.LeftButton)
        assert not window.recording_banner.isVisible()
        second = session.recording_path
        assert second != first and second.exists()
        qtbot.waitUntil(lambda: f"● recording {second}" in window.recording_label.text(), timeout=LIMIT_MS)
        assert [e["kind"] for e in session.view.events].count("recording_resumed") == 1

        window.disconnect()
        assert window.recording_label.text() == "not recording"  # not the stopped session's "● recording"
        fill(folder, 16_000, "filler3")
        window.start_demo()
        qtbot.waitUntil(window.recording_banner.isVisible, timeout=LIMIT_MS)
        session = window.session
        window.close()  # stops the session while its recording has failed; raises nothing
        assert window.session is None and session.recorder.state == "off"

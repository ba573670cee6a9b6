"""The window on the in-process simulated bridge: curves receive the pipeline's numbers, the
redraw timer keeps drawing, the link panel reports a healthy link."""

import numpy as np

from groundstation import quaternion
from tests.waiting import LIMIT_MS


def test_plotted_pitch_is_the_pipelines_ahf2_pitch(window, qtbot):
    window.start_demo()
    session = window.session
    qtbot.waitUntil(lambda: len(session.view.imu) > 150 and window.live_view.frames_drawn > 10, timeout=LIMIT_MS)
    ahf = next(c for s, c in window.live_view.attitude.curves if s.quantity == "ahf2_pitch_deg")  # shown at first
    onboard = next(c for s, c in window.live_view.attitude.curves if s.quantity == "onboard_pitch_deg")
    t, pitch = ahf.xData[-1], ahf.yData[-1]
    imu = session.view.imu.array()
    row = imu[np.flatnonzero(imu[:, session.view.imu.columns.index("time_s")] == t)[0]]
    q = [row[session.view.imu.columns.index(f"ahf2_q{c}")] for c in "wxyz"]
    # The window converts a block of rows, this line one row: NumPy may take another SIMD loop for each
    # (arcsin, arctan2: last-bit differences on AVX-512), a few float64 ulp that the float32 curve rounds
    # away, or to the neighbouring float32 at a rounding boundary: one float32 ulp at most.
    expected = np.float32(np.degrees(quaternion.to_euler_zyx(np.array(q))[1]))
    assert abs(pitch - expected) <= abs(np.spacing(expected))  # spacing is negative for a negative number
    assert f"<td>AHF2</td><td align=right>&nbsp;{pitch:+.2f}</td>" in window.live_view.attitude.read_at(t)  # the crosshair's readout: AHF2's row, pitch column
    assert len(window.live_view.attitude.drawn(onboard)[0]) > 100  # the aircraft's own estimate is drawn too
    assert window.link_panel.headline.text() == "LINK OK"
    assert str(session.recording_path) in window.recording_label.text()


def test_redraw_timer_draws_for_seconds_without_crashing(window, qtbot):
    """PySide6 6.12.0 aborts on Python 3.11 within a second of plotting; this is the guard."""
    window.start_demo()
    view = window.live_view
    qtbot.wait(1500)
    view.window_box.setCurrentText("whole session")
    view.tabs.setCurrentWidget(view.sensors)
    qtbot.wait(1000)
    view.tabs.setCurrentWidget(view.attitude)
    before = view.frames_drawn
    qtbot.waitUntil(lambda: view.frames_drawn - before >= 20, timeout=LIMIT_MS)  # about 30 per second at rest
    window.grab()  # a full paint of every plot

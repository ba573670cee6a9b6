"""A recording in the window: the transport pauses, steps, changes speed and seeks; a seek shows the
estimates the whole flight leads to at that point, exactly as a headless replay computes them."""

import numpy as np

from groundstation.recording import open_recording
from groundstation.session.replay import replay


def samples(window):
    return len(window.session.pipeline.imu)


def test_transport_pause_step_speed_and_seek(window, qtbot, recording):
    window.open_recording(recording)
    bar = window.replay_bar
    assert bar.isVisible() and window.banner.isHidden()
    qtbot.waitUntil(lambda: window.live_view.frames_drawn > 3 and samples(window) > 20, timeout=5000)

    bar.play_button.click()  # pause: nothing more arrives
    paused_at = samples(window)
    qtbot.wait(300)
    assert samples(window) == paused_at and bar.play_button.text() == "Play"
    bar.step_button.click()
    assert samples(window) == paused_at + 1

    bar.speed_box.setCurrentIndex(bar.speed_box.findData(4.0))
    assert window.session.source.speed == 4.0

    window.seek(20.0)
    qtbot.waitUntil(lambda: window.seeking is None, timeout=10000)
    session = window.session
    assert session.source.paused and session.source.speed == 4.0  # kept across the seek
    assert abs(session.source.position_s - 20.0) < 0.05
    imu = session.pipeline.imu.array()
    headless = replay(open_recording(recording)).imu.array()
    np.testing.assert_array_equal(imu, headless[: len(imu)])  # the flight up to the seek, bit for bit
    bar.play_button.click()
    ahf = next(c for s, c in window.live_view.attitude.curves if s.quantity == "ahf_pitch_deg")
    qtbot.waitUntil(lambda: ahf.xData is not None and len(ahf.xData) and ahf.xData[-1] > 21.0, timeout=3000)

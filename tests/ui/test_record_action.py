"""Issue 12: start and stop recording from the window, with the file name and size shown; a replay
cannot be re-recorded."""

from groundstation.recording import open_recording
from groundstation.session_makers.pipeline import Pipeline

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_recording_stops_and_starts_a_new_file_that_replays(window, qtbot):
    window.start_demo()
    session, action = window.session, window.record_action
    qtbot.waitUntil(lambda: session.recorder.bytes_written > 20_000, timeout=LIMIT_MS)
    first = session.recording_path
    assert action.isEnabled() and action.text() == "Stop recording"
    action.trigger()
    assert session.recorder.state == "off" and action.text() == "Start recording"
    size = first.stat().st_size
    assert 0 < size - session.recorder.bytes_written < 100  # closed: all of it on disk, and the END record
    assert str(first) in window.recording_label.text() and "not recording" in window.recording_label.text()
    assert f"{session.recorder.bytes_written / 1e6:.1f} MB" in window.recording_label.text()
    qtbot.wait(500)
    assert first.stat().st_size == size and session.running  # the session goes on, the file does not grow
    action.trigger()
    second = session.recording_path
    assert second != first and second.parent == first.parent and session.recorder.state == "recording"
    qtbot.waitUntil(lambda: session.recorder.bytes_written > 20_000, timeout=LIMIT_MS)
    window.tick()
    window.ticks = 0  # the next tick refreshes the figures
    qtbot.waitUntil(lambda: f"● recording {second}" in window.recording_label.text(), timeout=LIMIT_MS)
    window.disconnect()
    pipeline = Pipeline(("ahf",))  # the new file stands on its own: a CONFIG frame and the samples
    for t_host_ns, data in open_recording(second).chunks():
        pipeline.feed(t_host_ns, data)
    assert pipeline.config and len(pipeline.imu) > 100


def test_a_replay_offers_no_recording(window, qtbot, recording):
    open_file(window, qtbot, recording)
    assert window.session is not None and not window.record_action.isEnabled()
    window.toggle_recording()
    assert window.session.recording_path is None
    window.disconnect()
    assert not window.record_action.isEnabled()

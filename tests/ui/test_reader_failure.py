"""A failure in the live reader thread shows in the window's banner (issue 22), never a dead thread
behind a display that still looks live."""

from tests.session.test_unexpected_frames import FailingPipeline
from tests.waiting import LIMIT_MS


def test_a_failure_in_the_reader_shows_in_the_banner(window, qtbot, monkeypatch):
    monkeypatch.setattr("groundstation.session_makers.pipeline.Pipeline", FailingPipeline)  # open_session imports it when it runs
    window.connect_serial("sim:")
    session = window.session
    assert session is not None
    qtbot.waitUntil(lambda: window.banner.isVisible(), timeout=LIMIT_MS)
    assert not session.running
    assert "ZeroDivisionError: float division by zero" in window.banner.text()

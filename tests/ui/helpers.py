"""Shared steps of the window tests."""

from tests.waiting import LIMIT_MS


def open_file(window, qtbot, path, timeout_ms: int = LIMIT_MS) -> None:
    """Open ``path`` as File > Open does and wait until it is computed (or refused, in the banner)."""
    window.open_recording(path)
    qtbot.waitUntil(lambda: window.loading is None, timeout=timeout_ms)


def play_to_the_end(window, qtbot, timeout_ms: int = LIMIT_MS) -> None:
    """Play the replay (paused or not) at 64x until the clock reaches the end of the data."""
    window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(64.0))
    if window.session.source.paused:
        window.replay_bar.play_button.click()
    qtbot.waitUntil(lambda: not window.session.running, timeout=timeout_ms)

"""The keyboard: Space pauses (the view live, the playback in a replay), ←/→ step, Home/End, Ctrl+O,
Ctrl+E; the Help menu lists every shortcut."""

import pytest
from PySide6 import QtCore, QtWidgets

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def key(qtbot, window, name, modifier=QtCore.Qt.NoModifier):
    qtbot.keyClick(window.live_view, name, modifier)  # wherever the focus is in the window


def x_range(window):
    return window.live_view.attitude.items[0].getViewBox().viewRange()[0]


def test_keys_live(window, qtbot):
    window.start_demo()
    qtbot.waitUntil(lambda: window.live_view.frames_drawn > 20, timeout=LIMIT_MS)
    key(qtbot, window, QtCore.Qt.Key_Space)
    assert window.live_view.paused
    low, high = x_range(window)
    key(qtbot, window, QtCore.Qt.Key_Left)
    assert x_range(window)[0] == pytest.approx(low - 0.1 * (high - low))
    key(qtbot, window, QtCore.Qt.Key_Home)
    assert x_range(window)[0] == pytest.approx(window.live_view.series["imu"].start_s)
    key(qtbot, window, QtCore.Qt.Key_End)
    assert not window.live_view.paused
    key(qtbot, window, QtCore.Qt.Key_E, QtCore.Qt.ControlModifier)
    dialogs = [w for w in QtWidgets.QApplication.topLevelWidgets() if type(w).__name__ == "ExportDialog" and w.isVisible()]
    assert dialogs
    for dialog in dialogs:
        dialog.close()


def test_keys_in_a_replay(window, qtbot, recording):
    open_file(window, qtbot, recording)
    source = window.session.source
    key(qtbot, window, QtCore.Qt.Key_Space)
    assert source.paused and window.replay_bar.play_button.text() == "Play"
    key(qtbot, window, QtCore.Qt.Key_End)  # seeks move the clock at once
    assert source.position_s == source.duration_s
    key(qtbot, window, QtCore.Qt.Key_Home)
    assert source.position_s == 0.0
    key(qtbot, window, QtCore.Qt.Key_Right)
    assert source.position_s == 5.0
    assert source.paused and window.session.source is source  # kept across the seeks


def test_help_lists_every_shortcut(window):
    keys = {k for k, _ in window.shortcuts()}
    assert {"Space", "Left", "Right", "Home", "End", "Ctrl+O", "Ctrl+E"} <= keys
    box = window.show_shortcuts()
    assert all(k in box.text() for k in keys)
    box.close()

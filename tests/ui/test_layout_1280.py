"""The window at 1280x800 (issue 34): nothing in the right column is wider than its room (it was clipped on
flight logs), the Estimators panel's Apply is in sight without scrolling, the status bar cuts a long recording
path in the middle (its whole text in the tooltip), and the plots stay where they are while the progress bar, the
replay bar and the banners come and go (the layout jumped), with no empty band kept for them on a live session
(a strip reserved for the bars showed as 30 px of nothing above every live plot)."""

from PySide6 import QtCore, QtWidgets

from tests.ui.helpers import open_file
from tests.ui.test_replay import flightlog
from tests.waiting import LIMIT_MS

HOP = "px4_fmuv5_quad_hop.ulg"


def settle(qtbot, window):
    qtbot.waitUntil(lambda: window.isVisible(), timeout=LIMIT_MS)
    qtbot.wait(100)


def plots_top(window) -> int:
    return window.live_view.tabs.mapTo(window, QtCore.QPoint(0, 0)).y()


# What shows something: an empty container (a strip kept for a bar that is hidden) does not count.
DRAWN = (QtWidgets.QLabel, QtWidgets.QAbstractButton, QtWidgets.QComboBox, QtWidgets.QProgressBar, QtWidgets.QSlider)


def longest_empty_band(window) -> int:
    """The most pixel rows in a row between the connection bar and the plots' tabs that no visible widget draws on."""
    top = window.bar.mapTo(window, QtCore.QPoint(0, window.bar.height())).y()
    covered = [False] * (plots_top(window) - top)
    for widget in window.centralWidget().findChildren(QtWidgets.QWidget):
        if isinstance(widget, DRAWN) and widget.isVisible():
            y = widget.mapTo(window, QtCore.QPoint(0, 0)).y() - top
            for row in range(max(y, 0), min(y + widget.height(), len(covered))):
                covered[row] = True
    longest = run = 0
    for row in covered:
        run = 0 if row else run + 1
        longest = max(longest, run)
    return longest


def test_a_flight_log_fits_the_right_column_and_apply_is_in_sight(window, qtbot):
    window.resize(1280, 800)
    open_file(window, qtbot, flightlog(HOP))
    settle(qtbot, window)
    scroll = window.splitter.widget(1)
    assert scroll.widget().minimumSizeHint().width() <= scroll.viewport().width()
    window.controls.setCurrentWidget(window.estimator_panel)
    qtbot.wait(50)
    apply = next(b for b in window.estimator_panel.findChildren(QtWidgets.QPushButton) if b.text() == "Apply")
    bottom = apply.mapTo(scroll.viewport(), QtCore.QPoint(0, apply.height())).y()
    assert scroll.verticalScrollBar().value() == 0 and bottom <= scroll.viewport().height()


def test_the_status_bar_cuts_a_long_text_in_the_middle_and_keeps_it_whole_in_the_tooltip(window, qtbot):
    window.resize(1280, 800)
    settle(qtbot, window)
    path = "/home/pilot/" + "a-very-long-folder-name/" * 8 + "2026-12-02_04-12-33.gsrec"
    text = f"● recording {path}  (1.2 MB)"
    window.recording_label.setText(text)
    qtbot.wait(50)
    label, bar = window.recording_label, window.statusBar()
    assert label.text() == text and label.toolTip() == text
    shown = label.shown()
    assert "…" in shown and shown.startswith("● recording /home") and shown.endswith("(1.2 MB)")
    assert label.fontMetrics().horizontalAdvance(shown) <= label.contentsRect().width()
    assert label.mapTo(window, QtCore.QPoint(label.width(), 0)).x() <= bar.width()


def test_a_live_session_has_no_empty_band_over_its_plots(window, qtbot):
    window.resize(1280, 800)
    window.start_demo()
    settle(qtbot, window)
    qtbot.waitUntil(lambda: window.live_view.frames_drawn > 0, timeout=LIMIT_MS)
    assert longest_empty_band(window) <= 8  # a layout's spacing, not a row


def test_the_plots_stay_put_while_bars_and_banners_come_and_go(window, qtbot):
    window.resize(1280, 800)
    window.start_demo()  # from a live session, as a user opens a file
    settle(qtbot, window)
    top = plots_top(window)
    window.open_recording(flightlog(HOP))
    qtbot.waitUntil(lambda: window.loading_row.isVisible(), timeout=LIMIT_MS)
    qtbot.wait(20)
    assert plots_top(window) == top  # the progress bar
    qtbot.waitUntil(lambda: window.loading is None, timeout=LIMIT_MS)
    qtbot.wait(50)
    assert window.replay_bar.isVisible() and plots_top(window) == top  # the replay bar
    window.show_error("a long message about what went wrong " * 4)
    qtbot.wait(50)
    assert window.banner.isVisible() and plots_top(window) == top  # the red banner
    bottom = window.banner.mapTo(window, QtCore.QPoint(0, window.banner.height())).y()
    assert bottom > top  # over the plots, not above them
    window.show_error(None)
    qtbot.wait(50)
    assert plots_top(window) == top

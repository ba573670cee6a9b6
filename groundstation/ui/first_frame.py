"""The window's first paint: what the app waits for before it loads the estimators' compiled kernels
(``ui.app.run``), and the benchmark's stopwatch (``bench/bench_first_frame.py``).

With ``GROUNDSTATION_FIRST_FRAME=1`` in the environment the app prints the process's CPU seconds (every
thread's, since the process started; ``groundstation.stopwatch``) at

- ``first paint``: the main window's first paint event (the window on screen, its plots still empty);
- ``first data``: the first paint of any of its widgets after the live view drew with rows of the
  session taken (``LiveView.frames_drawn``, ``Series.taken``): a curve with data on screen; then the
  estimators not compiled then (a first start: their kernels compiling in the background);
- ``every estimator``: a file shown without some estimators (a first start), once they joined it;

then closes the window (the session stops, the recording closes, as at the close button) and so quits.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from groundstation import stopwatch


class _FirstPaint(QtCore.QObject):
    def __init__(self, widget: QtWidgets.QWidget, callback):
        super().__init__(widget)
        self.callback = callback
        widget.installEventFilter(self)

    def eventFilter(self, watched, event) -> bool:
        if event.type() == QtCore.QEvent.Paint:
            watched.removeEventFilter(self)
            self.callback()
        return False


def on_first_paint(widget: QtWidgets.QWidget, callback) -> None:
    """``callback()`` at ``widget``'s first paint event, just before it paints (so it must not take long)."""
    _FirstPaint(widget, callback)


class FirstFrame(QtCore.QObject):
    """Notes ``window``'s first paint and first data (``moments``, and printed). The whole application's
    events are watched only once the live view has drawn (for the first paint of a plot's viewport):
    before that, a filter on every event would add its own cost to what is measured."""

    def __init__(self, app: QtWidgets.QApplication, window):
        super().__init__(window)
        self.app = app
        self.window = window
        self.moments: dict[str, float] = {}
        self._frames_drawn = 0
        on_first_paint(window, lambda: self._note("first paint"))
        window.timer.timeout.connect(self._drawn)  # after the window's own redraw tick

    def _drawn(self) -> None:
        view = self.window.live_view
        # A draw counts once rows were taken: a new session's plots are drawn empty too (``stale``).
        drew, self._frames_drawn = view.frames_drawn > self._frames_drawn, view.frames_drawn
        if drew and any(series.taken for series in view.series.values()) and "first paint" in self.moments:
            self.window.timer.timeout.disconnect(self._drawn)
            self.app.installEventFilter(self)

    def eventFilter(self, watched, event) -> bool:
        if event.type() == QtCore.QEvent.Paint and isinstance(watched, QtWidgets.QWidget) and watched.window() is self.window:
            self.app.removeEventFilter(self)
            self._note("first data")
            session = self.window.session
            stopwatch.note_uncompiled(session.view.uncompiled())
            if session.seekable and session.view.uncompiled():  # a file: its other estimators join when compiled
                self.window.timer.timeout.connect(self._every_estimator)
            else:
                QtCore.QTimer.singleShot(0, self.window.close)
        return False

    def _every_estimator(self) -> None:
        session = self.window.session
        if session is not None and not session.view.uncompiled():
            self.window.timer.timeout.disconnect(self._every_estimator)
            self._note("every estimator")
            QtCore.QTimer.singleShot(0, self.window.close)

    def _note(self, moment: str) -> None:
        self.moments[moment] = stopwatch.note(moment)


def watch(app: QtWidgets.QApplication, window) -> FirstFrame | None:
    """A ``FirstFrame`` on ``window`` when the environment asks for one."""
    return FirstFrame(app, window) if stopwatch.wanted() else None

"""The start's two moments, for ``bench/bench_first_frame.py``: with ``GROUNDSTATION_FIRST_FRAME=1`` in the
environment the app prints the process's CPU seconds (every thread's, since the process started) at

- ``first paint``: the main window's first paint event (the window on screen, its plots still empty);
- ``first data``: the first paint of any of its widgets after the live view drew a sample
  (``LiveView.frames_drawn``): a curve with data on screen;

then closes the window (the session stops, the recording closes, as at the close button) and so quits.
Without the variable nothing here runs.
"""

from __future__ import annotations

import os
import time

from PySide6 import QtCore, QtWidgets

ENV = "GROUNDSTATION_FIRST_FRAME"


class FirstFrame(QtCore.QObject):
    """Watches ``window``'s paint events; ``moments`` holds what it printed. The whole application's
    events are watched only once the live view has drawn (for the first paint of a plot's viewport):
    before that, a filter on every event would add its own cost to what is measured."""

    def __init__(self, app: QtWidgets.QApplication, window):
        super().__init__(window)
        self.app = app
        self.window = window
        self.moments: dict[str, float] = {}
        window.installEventFilter(self)
        window.timer.timeout.connect(self._drawn)  # after the window's own redraw tick

    def _drawn(self) -> None:
        if self.window.live_view.frames_drawn and "first paint" in self.moments:
            self.window.timer.timeout.disconnect(self._drawn)
            self.app.installEventFilter(self)

    def eventFilter(self, watched, event) -> bool:
        if event.type() != QtCore.QEvent.Paint or not isinstance(watched, QtWidgets.QWidget) or watched.window() is not self.window:
            return False
        if "first paint" not in self.moments:
            self._note("first paint")
        elif self.window.live_view.frames_drawn and "first data" not in self.moments:
            self._note("first data")
            self.app.removeEventFilter(self)
            QtCore.QTimer.singleShot(0, self.window.close)
        return False

    def _note(self, moment: str) -> None:
        self.moments[moment] = time.process_time()
        print(f"{moment} {self.moments[moment]:.3f}", flush=True)


def watch(app: QtWidgets.QApplication, window) -> FirstFrame | None:
    """A ``FirstFrame`` on ``window`` when the environment asks for one."""
    return FirstFrame(app, window) if os.environ.get(ENV) else None

"""Starting the Qt application with the main window on a source."""

from __future__ import annotations

import os
import signal
import sys

from groundstation.errors import UserError

ORGANIZATION = APPLICATION = "groundstation"


def check_display() -> None:
    """Qt aborts the process when it finds no display; say so first, plainly."""
    if sys.platform.startswith("linux") and not any(os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")):
        raise UserError("no display found (DISPLAY and WAYLAND_DISPLAY are unset); run it in a desktop session, "
                        "or under Xvfb (xvfb-run groundstation app)")


def run(port: str | None, baud: int | None, recording: str | None, sessions) -> int:
    """Open the window on ``recording``, else ``port``, else the simulated bridge; ``sessions`` opens
    them (``session.factory.Sessions``)."""
    check_display()
    import pyqtgraph as pg
    from PySide6 import QtCore, QtWidgets

    from groundstation.ui import first_frame
    from groundstation.ui.main_window import MainWindow

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setOrganizationName(ORGANIZATION)
    app.setApplicationName(APPLICATION)
    pg.setConfigOptions(antialias=False)  # antialiased lines cost several times more per frame
    window = MainWindow(QtCore.QSettings(), sessions)
    first_frame.watch(app, window)  # the benchmark's stopwatch, when asked for
    # Ctrl-C or a kill closes the window as its close button does: the session stops, the recording
    # is closed and the settings saved. (Python runs the handler at the redraw timer's next tick.)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: window.close())

    def open_source() -> None:
        prepare_estimators(app).finish(window)
        if recording:
            window.open_recording(recording)
        elif port:
            window.connect_serial(port, baud or 0)
        else:
            window.start_demo("no port given: streaming from the simulated bridge")

    # The window on screen first, then the estimators' kernels (a second warm) and the source: nothing is
    # read from the source before its session's estimators exist, so no sample waits or is lost.
    first_frame.on_first_paint(window, lambda: QtCore.QTimer.singleShot(0, open_source))
    window.show()
    return app.exec()


def prepare_estimators(app):
    """The live session's estimators made once, before the source opens, under a splash screen that
    says so. The first start on a machine compiles their numba kernels (some seconds; later starts, also after a re-install, load
    them from the user's cache folder: ``estimation.compiled_cache``), which would otherwise freeze the window without a word."""
    from PySide6 import QtCore, QtGui, QtWidgets

    from groundstation.estimation import create, live_estimators

    blank = QtGui.QPixmap(560, 90)
    blank.fill(QtGui.QColor("#263238"))
    splash = QtWidgets.QSplashScreen(blank)
    splash.show()
    for name in live_estimators():
        splash.showMessage(f"groundstation: preparing the {name} estimator…\n(compiled on the first start on this "
                           "machine, then loaded from a cache)", QtCore.Qt.AlignCenter, QtGui.QColor("white"))
        app.processEvents()
        create(name)
    return splash

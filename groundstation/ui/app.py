"""Starting the Qt application with the main window on a source."""

from __future__ import annotations

import os
import signal
import sys

from groundstation.errors import UserError
from groundstation.heap import keep_large_blocks_out_of_the_heap

ORGANIZATION = APPLICATION = "groundstation"


# The system libraries Qt's xcb platform plugin loads on Linux (its wheel does not carry them), by
# soname, with the package that holds each on Debian/Ubuntu and on Fedora. Qt aborts the process with a
# list of plugins when one is missing; a bare desktop install often lacks libxcb-cursor0.
QT_XCB_LIBRARIES = {
    "libxcb.so.1": ("libxcb1", "libxcb"),
    "libxcb-cursor.so.0": ("libxcb-cursor0", "xcb-util-cursor"),
    "libxkbcommon-x11.so.0": ("libxkbcommon-x11-0", "libxkbcommon-x11"),
    "libxcb-icccm.so.4": ("libxcb-icccm4", "xcb-util-wm"),
    "libxcb-image.so.0": ("libxcb-image0", "xcb-util-image"),
    "libxcb-keysyms.so.1": ("libxcb-keysyms1", "xcb-util-keysyms"),
    "libxcb-randr.so.0": ("libxcb-randr0", "libxcb"),
    "libxcb-render-util.so.0": ("libxcb-render-util0", "xcb-util-renderutil"),
    "libxcb-xinerama.so.0": ("libxcb-xinerama0", "libxcb"),
    "libxcb-xkb.so.1": ("libxcb-xkb1", "libxcb"),
    "libxcb-shape.so.0": ("libxcb-shape0", "libxcb"),
    "libEGL.so.1": ("libegl1", "libglvnd-egl"),
    "libGL.so.1": ("libgl1", "libglvnd-glx"),
    "libfontconfig.so.1": ("libfontconfig1", "fontconfig"),
    "libdbus-1.so.3": ("libdbus-1-3", "dbus-libs"),
}


def check_display() -> None:
    """Qt aborts the process when it finds no display, or no library its platform plugin needs; say so
    first, plainly."""
    if not sys.platform.startswith("linux"):
        return
    if not any(os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")):
        raise UserError("no display found (DISPLAY and WAYLAND_DISPLAY are unset); run it in a desktop session, "
                        "or under Xvfb (xvfb-run groundstation app)")
    # X11's plugin: asked for, or Qt's choice without a Wayland session (on Wayland Qt 6 takes its own plugin)
    if os.environ.get("QT_QPA_PLATFORM", "" if os.environ.get("WAYLAND_DISPLAY") else "xcb") == "xcb":
        check_libraries(QT_XCB_LIBRARIES)
        check_x_server(os.environ.get("DISPLAY", ""))


def check_x_server(display: str) -> None:
    """UserError when the X server ``display`` names does not answer (Qt aborts with a list of plugins)."""
    import ctypes

    xcb = ctypes.CDLL("libxcb.so.1")
    xcb.xcb_connect.restype = ctypes.c_void_p
    xcb.xcb_connection_has_error.argtypes = xcb.xcb_disconnect.argtypes = [ctypes.c_void_p]
    connection = xcb.xcb_connect(display.encode(), None)
    try:
        if xcb.xcb_connection_has_error(connection):
            raise UserError(f"no X display answers at DISPLAY={display!r}; run it in a desktop session, or under "
                            "Xvfb (xvfb-run groundstation app)")
    finally:
        xcb.xcb_disconnect(connection)


def check_libraries(libraries: dict[str, tuple[str, str]]) -> None:
    """UserError naming the packages to install when any of ``libraries`` (soname: (Debian package,
    Fedora package)) cannot be loaded."""
    import ctypes

    missing = []
    for soname, packages in libraries.items():
        try:
            ctypes.CDLL(soname)
        except OSError:
            missing.append(packages)
    if missing:
        debian, fedora = (" ".join(dict.fromkeys(names)) for names in zip(*missing))
        raise UserError(f"Qt cannot open a window: system libraries are missing; install them with "
                        f"`sudo apt install {debian}` (Debian, Ubuntu) or `sudo dnf install {fedora}` (Fedora)")


def close_on_signals(window) -> None:
    """Ctrl-C or a kill closes the window as its close button does: the session stops, the recording is
    closed and the settings saved. Python runs the handler between two bytecodes of whatever the main
    thread runs then (the redraw timer's tick, say, holding the session's lock while it reads a table), so
    the handler only asks the event loop to close once that code is done: closing there would wait for the
    reader thread, which waits for the lock (a kill that never ended, seen with ``py-spy dump``)."""
    from PySide6 import QtCore

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: QtCore.QTimer.singleShot(0, window.close))


def run(port: str | None, baud: int | None, recording: str | None, sessions) -> int:
    """Open the window on ``recording``, else ``port``, else the simulated bridge; ``sessions`` opens
    them (``session_makers.factory.Sessions``)."""
    check_display()
    keep_large_blocks_out_of_the_heap()
    import pyqtgraph as pg
    from PySide6 import QtCore, QtWidgets

    from groundstation.ui import first_frame
    from groundstation.ui.main_window import MainWindow
    from groundstation.ui.window_settings import window_settings

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(sys.argv[:1])
    app.setOrganizationName(ORGANIZATION)
    app.setApplicationName(APPLICATION)
    pg.setConfigOptions(antialias=False)  # antialiased lines cost several times more per frame
    # A settings file per window open at once (``ui.window_settings``): a second window overwrites nothing of the first's.
    settings, claim = window_settings(lambda name: QtCore.QSettings(ORGANIZATION, name), APPLICATION)
    window = MainWindow(settings, sessions)
    window.setWindowTitle(claim.title(window.windowTitle()))
    first_frame.watch(app, window)  # the benchmark's stopwatch, when asked for
    close_on_signals(window)

    def open_source() -> None:
        if recording:
            window.open_recording(recording)
        elif port:
            window.connect_serial(port, baud or 0)
        else:
            window.start_demo("no port given: streaming from the simulated bridge")

    # The window on screen first, then the source: its session starts with the estimators whose kernels
    # numba has in its cache and runs the others interpreted while another process compiles them
    # (``session_parts.estimators.EstimatorBank``), so the first start shows data at once too, and nothing in
    # this process compiles for seconds: Ctrl-C and Close are answered at the next tick.
    first_frame.on_first_paint(window, lambda: QtCore.QTimer.singleShot(0, open_source))
    window.show()
    try:
        return app.exec()
    finally:
        claim.release()

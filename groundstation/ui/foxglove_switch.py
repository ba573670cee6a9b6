"""File > Serve to Foxglove: while it is checked, the window's session is served to Foxglove clients
(``export.foxglove_live``) on 127.0.0.1 and the port remembered in the settings (8765, Foxglove's own
default), and the status bar says the address, the clients and the messages dropped for slow ones; a port
that cannot be had is said in the red banner. Web pages are served (those of this machine, Foxglove's and
Lichtblick's web apps) unless the setting ``foxglove_web_apps`` is false."""

from __future__ import annotations

from PySide6 import QtCore, QtGui

from groundstation.errors import UserError
from groundstation.export.foxglove_live import FoxgloveBridge
from groundstation.session.view import Session

DEFAULT_PORT = 8765


class FoxgloveSwitch(QtCore.QObject):
    def __init__(self, settings: QtCore.QSettings, show_status, show_error, parent=None):
        super().__init__(parent)
        self.settings = settings
        self._show_status = show_status  # (text) -> None: the status bar
        self._show_error = show_error  # (text | None) -> None: the red banner
        self.action = QtGui.QAction("Serve live session to &Foxglove", self)
        self.action.setCheckable(True)
        self.action.toggled.connect(self._toggled)
        self.bridge: FoxgloveBridge | None = None
        self.session: Session | None = None
        self._status = ""
        self._timer = QtCore.QTimer(self)  # the clients and drops change while the switch is on
        self._timer.setInterval(1000)
        self._timer.timeout.connect(self._show_bridge_status)

    @property
    def port(self) -> int:
        return int(self.settings.value("foxglove_port", DEFAULT_PORT))

    def follow(self, session: Session | None) -> None:
        """The window's session changed: serve the new one (or none)."""
        self.session = session
        if self.action.isChecked():
            self._stop()
            self._start()

    def _toggled(self, on: bool) -> None:
        self._stop()
        if on:
            self._start()
        else:
            self._show_status("Foxglove: off")

    def _start(self) -> None:
        try:
            web_apps = str(self.settings.value("foxglove_web_apps", "true")).lower() in ("true", "1")
            self.bridge = FoxgloveBridge("127.0.0.1", self.port, web_apps=web_apps)
        except UserError as error:
            self._show_error(str(error))
            self.action.setChecked(False)
            return
        if self.session is not None:
            self.bridge.serve(self.session, history=False)
        self._status = ""
        self._show_bridge_status()
        self._timer.start()

    def _show_bridge_status(self) -> None:
        text = self.bridge.status_text()
        if text != self._status:
            self._status = text
            self._show_status(text)

    def _stop(self) -> None:
        self._timer.stop()
        if self.bridge is not None:
            self.bridge.close()
            self.bridge = None

"""File > Serve to Foxglove: while it is checked, the window's session is served to Foxglove clients
(``export.foxglove_live``) on 127.0.0.1 and the port remembered in the settings (8765, Foxglove's own
default), and the status bar says the address; a port that cannot be had is said in the red banner."""

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
            self.bridge = FoxgloveBridge("127.0.0.1", self.port)
        except UserError as error:
            self._show_error(str(error))
            self.action.setChecked(False)
            return
        if self.session is not None:
            self.bridge.serve(self.session, history=False)
        self._show_status(f"Foxglove: {self.bridge.address}")

    def _stop(self) -> None:
        if self.bridge is not None:
            self.bridge.close()
            self.bridge = None

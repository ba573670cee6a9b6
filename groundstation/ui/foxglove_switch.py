"""Serve to Foxglove: while its action is checked, a session is served to Foxglove clients
(``export.foxglove_live``) on 127.0.0.1 and a port (8765, Foxglove's own default, or the one chosen in
``choose_port``), and the status line says the address, the clients and the messages dropped for slow ones.
A port already served (a second window, another session of this one) is said in the red banner and the
next free one is served instead; a port that cannot be had at all is said there too. The window's own
session remembers its port in the window's settings; each added session (``ui.session_list``) has a switch
of its own. Web pages are served (those of this machine, Foxglove's and Lichtblick's web apps) unless the
setting ``foxglove_web_apps`` is false."""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from groundstation.errors import UserError
from groundstation.export.foxglove_live import FoxgloveBridge, PortTaken
from groundstation.session.view import Session

DEFAULT_PORT = 8765
NEXT_PORTS = 20  # a taken port: this many after it are tried before giving up
PORT_KEY = "foxglove_port"


class FoxgloveSwitch(QtCore.QObject):
    """``remember``: keep the port in ``settings`` (the window's session); else it lives as long as the switch."""

    def __init__(self, settings: QtCore.QSettings, show_status, show_error, parent=None, *, remember: bool = True,
                 port: int | None = None, text: str = "Serve live session to &Foxglove"):
        super().__init__(parent)
        self.settings = settings
        self._remember = remember
        self._port = port
        self._show_status = show_status  # (text) -> None: the status bar
        self._show_error = show_error  # (text | None) -> None: the red banner
        self.action = QtGui.QAction(text, self)
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
        """The port asked for (a taken one: the bridge serves on the next free one, ``bridge.port``)."""
        if self._remember:
            return int(self.settings.value(PORT_KEY, DEFAULT_PORT))
        return DEFAULT_PORT if self._port is None else self._port

    def set_port(self, port: int) -> None:
        """Serve on ``port`` from now on (at once if serving)."""
        if self._remember:
            self.settings.setValue(PORT_KEY, port)
        else:
            self._port = port
        if self.action.isChecked():
            self._stop()
            self._start()

    def choose_port(self) -> QtWidgets.QInputDialog:
        """A dialog asking the port (its OK serves there); shown, not waited for."""
        parent = self.parent() if isinstance(self.parent(), QtWidgets.QWidget) else None
        dialog = QtWidgets.QInputDialog(parent)
        dialog.setWindowTitle("Foxglove port")
        dialog.setInputMode(QtWidgets.QInputDialog.IntInput)
        dialog.setIntRange(0, 65535)
        dialog.setIntValue(self.bridge.port if self.bridge is not None else self.port)
        dialog.setLabelText("Serve to Foxglove on port (0: any free one; a taken one: the next free)")
        dialog.intValueSelected.connect(self.set_port)
        dialog.open()
        return dialog

    def follow(self, session: Session | None) -> None:
        """The session to serve changed: serve the new one (or none)."""
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
        wanted = self.port
        tried = range(wanted, min(wanted + NEXT_PORTS, 65536)) if wanted else (0,)
        web_apps = str(self.settings.value("foxglove_web_apps", "true")).lower() in ("true", "1")
        for port in tried:
            try:
                self.bridge = FoxgloveBridge("127.0.0.1", port, web_apps=web_apps)
                break
            except PortTaken:
                continue
            except UserError as error:
                return self._refuse(str(error))
        else:
            return self._refuse(f"cannot serve Foxglove: ports {tried[0]} to {tried[-1]} are all taken; choose another "
                                "port (File > Foxglove port…)")
        if port != wanted:
            self._show_error(f"Foxglove port {wanted} is taken (another window or session serves there): serving on "
                             f"{self.bridge.port} instead (File > Foxglove port… chooses another)")
        if self.session is not None:
            self.bridge.serve(self.session, history=False)
        self._status = ""
        self._show_bridge_status()
        self._timer.start()

    def _refuse(self, message: str) -> None:
        self._show_error(message)
        self.action.setChecked(False)

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

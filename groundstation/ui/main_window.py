"""The main window: connection bar, live view, side panels, status bar; owns the current session.

One ``QTimer`` (``REDRAW_HZ``) pulls from the session's tables and redraws; the session's reader
thread never touches a widget. Problems (a busy port, an unreadable recording, a lost port) appear
in the red banner under the connection bar, never as a traceback.
"""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.errors import UserError
from groundstation.session.live import LiveSession
from groundstation.ui import sessions
from groundstation.ui.connection_bar import ConnectionBar
from groundstation.ui.link_panel import LinkPanel
from groundstation.ui.live_view import LiveView

REDRAW_HZ = 30
DEFAULT_HIDDEN = frozenset({"HF", "ECF", "CF1", "KF", "EKF"})  # comparison estimators start switched off


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, settings: QtCore.QSettings, recordings_dir: Path | None = None):
        super().__init__()
        self.setWindowTitle("groundstation")
        self.settings = settings
        self.recordings_dir = recordings_dir
        self.session: LiveSession | None = None
        self.bar = ConnectionBar()
        self.bar.select(settings.value("port"), int(settings.value("baud", 0) or 0))
        self.bar.connectRequested.connect(self.connect_serial)
        self.bar.disconnectRequested.connect(self.disconnect)
        self.bar.demoRequested.connect(self.start_demo)
        self.bar.recordingRequested.connect(self.choose_recording)
        self.banner = QtWidgets.QLabel()
        self.banner.setWordWrap(True)
        self.banner.setStyleSheet("background:#fde0e0; color:#8b0000; padding:6px; border:1px solid #e0a0a0")
        self.banner.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        self.banner.hide()
        self.live_view = LiveView()
        self.link_panel = LinkPanel()
        side = QtWidgets.QWidget()
        side_layout = QtWidgets.QVBoxLayout(side)
        side_layout.setContentsMargins(0, 0, 0, 0)
        side_layout.addWidget(self.link_panel)
        side_layout.addStretch(1)
        self.splitter = QtWidgets.QSplitter()
        self.splitter.addWidget(self.live_view)
        self.splitter.addWidget(side)
        self.splitter.setStretchFactor(0, 1)
        central = QtWidgets.QWidget()
        layout = QtWidgets.QVBoxLayout(central)
        layout.setContentsMargins(4, 0, 4, 0)
        layout.addWidget(self.bar)
        layout.addWidget(self.banner)
        layout.addWidget(self.splitter, 1)
        self.setCentralWidget(central)
        self.source_label = QtWidgets.QLabel("no source")
        self.recording_label = QtWidgets.QLabel("not recording")
        self.statusBar().addWidget(self.source_label, 1)
        self.statusBar().addPermanentWidget(self.recording_label)
        self.resize(1280, 800)
        self._restore_layout()
        self.timer = QtCore.QTimer(self, interval=1000 // REDRAW_HZ, timeout=self.tick)
        self.timer.start()

    # -- sessions -------------------------------------------------------------------------------

    def start_demo(self, note: str = "") -> None:
        self._start(lambda: sessions.start_demo(self.recordings_dir), note)

    def connect_serial(self, port: str, baud: int) -> None:
        self.settings.setValue("port", port)
        self.settings.setValue("baud", baud)
        self._start(lambda: sessions.start_serial(port, baud, self.recordings_dir))

    def open_recording(self, path) -> None:
        self._start(lambda: sessions.start_replay(path))

    def choose_recording(self) -> None:
        folder = self.settings.value("recording_folder", str(self.recordings_dir or Path.home()))
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open recording", folder, "Recordings (*.gsrec);;All files (*)")
        if path:
            self.settings.setValue("recording_folder", str(Path(path).parent))
            self.open_recording(path)

    def _start(self, start, note: str = "") -> None:
        """Stop the current session, then start another; a failure leaves none and says why."""
        self.disconnect()
        try:
            session = start()
        except UserError as error:
            self.show_error(str(error))
            return
        self.show_error(None)
        self.session = session
        self.live_view.set_session(session, self._hidden_curves())
        self.bar.set_connected(True)
        self.source_label.setText(f"{session.source.description}{'  —  ' + note if note else ''}")

    def disconnect(self) -> None:
        if self.session is None:
            return
        self.settings.setValue("hidden_curves", sorted(self._hidden_now()))
        session, self.session = self.session, None
        session.stop()
        self.bar.set_connected(False)
        self.source_label.setText(f"stopped: {session.source.description}")

    def show_error(self, message: str | None) -> None:
        self.banner.setText(message or "")
        self.banner.setVisible(bool(message))

    # -- the redraw timer -----------------------------------------------------------------------

    def tick(self) -> None:
        session = self.session
        self.link_panel.refresh(session)
        if session is None:
            return
        self.live_view.refresh()
        if session.error and not self.banner.isVisible():
            self.show_error(f"The session stopped: {session.error}")
        self.recording_label.setText(self._recording_text(session))

    @staticmethod
    def _recording_text(session: LiveSession) -> str:
        path = session.recording_path
        if path is None:
            return "not recording (replay)" if hasattr(session.source, "recording") else "not recording"
        try:
            size = path.stat().st_size
        except OSError:
            size = 0
        return f"● recording {path}  ({size / 1e6:.1f} MB)"

    # -- settings -------------------------------------------------------------------------------

    def _hidden_curves(self) -> frozenset[str]:
        stored = self.settings.value("hidden_curves")
        return DEFAULT_HIDDEN if stored is None else frozenset([stored] if isinstance(stored, str) else stored)

    def _hidden_now(self) -> set[str]:
        attitude = self.live_view.attitude
        return set() if attitude is None else {s.label for s, c in attitude.curves} - attitude.visible_labels()

    def _restore_layout(self) -> None:
        for key, restore in (("geometry", self.restoreGeometry), ("splitter", self.splitter.restoreState)):
            value = self.settings.value(key)
            if value is not None:
                restore(value)

    def closeEvent(self, event) -> None:
        self.disconnect()
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("splitter", self.splitter.saveState())
        self.settings.sync()
        super().closeEvent(event)

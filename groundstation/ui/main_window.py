"""The main window: connection bar, live view, side panels, status bar; owns the current session.

One ``QTimer`` (``REDRAW_HZ``) pulls from the session's tables and redraws; the session's reader
thread never touches a widget. Problems (a busy port, an unreadable recording, a lost port) appear
in the red banner under the connection bar, never as a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.errors import UserError
from groundstation.session.live import LiveSession
from groundstation.ui import sessions
from groundstation.ui.attitude_indicator import AttitudePanel
from groundstation.ui.connection_bar import ConnectionBar
from groundstation.ui.estimator_panel import TUNABLE, EstimatorPanel
from groundstation.ui.export_dialog import ExportDialog
from groundstation.ui.link_panel import LinkPanel
from groundstation.ui.live_view import LiveView
from groundstation.ui.replay_bar import ReplayBar
from groundstation.ui.uplink_panel import UplinkPanel

REDRAW_HZ = 30
# Every how many ticks the side panels redraw: the horizon at 15 Hz, figures and labels at 5 Hz
# (each repaint costs CPU under software rendering; people read numbers no faster).
HORIZON_EVERY, FIGURES_EVERY = 2, 6
# comparison estimators start switched off
DEFAULT_HIDDEN = frozenset({"AHF2", "HF", "ECF", "CF1", "KF", "EKF", "HF+mag", "ECF+mag", "MCF", "UKF", "SSSRUKF"})
# The curves of the versions that stored "hidden_curves" without "known_curves": any other label is new
# to the user's settings and starts hidden if it is in DEFAULT_HIDDEN.
FORMERLY_KNOWN = frozenset({"AHF", "onboard", "HF", "ECF"})


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, settings: QtCore.QSettings, recordings_dir: Path | None = None):
        super().__init__()
        self.setWindowTitle("groundstation")
        self.settings = settings
        self.recordings_dir = recordings_dir
        self.session: LiveSession | None = None
        self.seeking: sessions.ReplaySeek | None = None
        self.last_file: tuple[Path, float] | None = None  # the last session's recording and its length (s)
        self.bar = ConnectionBar()
        self.bar.select(settings.value("port"), int(settings.value("baud", 0) or 0))
        self.bar.connectRequested.connect(self.connect_serial)
        self.bar.disconnectRequested.connect(self.disconnect)
        self.bar.demoRequested.connect(self.start_demo)
        self.bar.recordingRequested.connect(self.choose_recording)
        self.bar.exportRequested.connect(self.export)
        self.banner = QtWidgets.QLabel()
        self.banner.setWordWrap(True)
        self.banner.setStyleSheet("background:#fde0e0; color:#8b0000; padding:6px; border:1px solid #e0a0a0")
        self.banner.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        self.banner.hide()
        self.replay_bar = ReplayBar()
        self.replay_bar.seekRequested.connect(self.seek)
        self.replay_bar.hide()
        self.live_view = LiveView(self._stored_hidden_curves())
        self.link_panel = LinkPanel()
        self.attitude_panel = AttitudePanel()
        self.estimator_panel = EstimatorPanel()
        self.estimator_panel.visibilityChanged.connect(self.live_view.set_visible)
        self.uplink_panel = UplinkPanel()
        self.estimator_panel.sendToAircraft.connect(self.uplink_panel.send_ahf)
        controls = QtWidgets.QTabWidget()
        controls.addTab(self.estimator_panel, "Estimators")
        controls.addTab(self.uplink_panel, "Uplink")
        side = QtWidgets.QWidget()
        side_layout = QtWidgets.QVBoxLayout(side)
        side_layout.setContentsMargins(0, 0, 0, 0)
        side_layout.addWidget(self.attitude_panel)
        side_layout.addWidget(self.link_panel)
        side_layout.addWidget(controls)
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
        layout.addWidget(self.replay_bar)
        layout.addWidget(self.splitter, 1)
        self.setCentralWidget(central)
        self.source_label = QtWidgets.QLabel("no source")
        self.recording_label = QtWidgets.QLabel("not recording")
        self.statusBar().addWidget(self.source_label, 1)
        self.statusBar().addPermanentWidget(self.recording_label)
        self.resize(1280, 800)
        self._restore_layout()
        self.ticks = 0
        self.timer = QtCore.QTimer(self, interval=1000 // REDRAW_HZ, timeout=self.tick)
        self.timer.start()

    # -- sessions -------------------------------------------------------------------------------

    def start_demo(self, note: str = "") -> None:
        self._start(lambda: sessions.start_demo(self.recordings_dir, self._stored_estimator_settings()), note)

    def connect_serial(self, port: str, baud: int) -> None:
        self.settings.setValue("port", port)
        self.settings.setValue("baud", baud)
        self._start(lambda: sessions.start_serial(port, baud, self.recordings_dir, self._stored_estimator_settings()))

    def open_recording(self, path) -> None:
        self._start(lambda: sessions.start_replay(path))

    def choose_recording(self) -> None:
        folder = self.settings.value("recording_folder", str(self.recordings_dir or Path.home()))
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open recording", folder, "Recordings (*.gsrec);;All files (*)")
        if path:
            self.settings.setValue("recording_folder", str(Path(path).parent))
            self.open_recording(path)

    def seek(self, t_s: float) -> None:
        """Restart the replay at ``t_s``, keeping its pause and speed; the new session is adopted
        by ``tick`` once the estimates before ``t_s`` are computed."""
        if self.seeking is not None:
            self.seeking.cancel()
            source = self.seeking.session.source
        elif self.session is not None:
            source = self.session.source
            self._stop_session()
        else:
            return
        self.seeking = sessions.ReplaySeek(source.recording, self.replay_bar.speed, source.paused, t_s)

    def _start(self, start, note: str = "") -> None:
        """Stop the current session, then start another; a failure leaves none and says why."""
        self.disconnect()
        try:
            session = start()
        except UserError as error:
            self.show_error(str(error))
            return
        self.show_error(None)
        self._adopt(session)
        self.source_label.setText(f"{session.source.description}{'  —  ' + note if note else ''}")

    def export(self) -> ExportDialog | None:
        """The export dialog on the current session's recording (or the last one's)."""
        file = self._session_file(self.session) if self.session is not None else self.last_file
        if file is None:
            self.show_error("Nothing to export yet: connect, start the simulated bridge or open a recording first.")
            return None
        dialog = ExportDialog(*file, parent=self)
        dialog.setModal(False)  # the live view goes on while it exports
        dialog.show()
        return dialog

    @staticmethod
    def _session_file(session: LiveSession) -> tuple[Path, float] | None:
        if hasattr(session.source, "recording"):
            return session.source.recording.path, session.source.duration_s
        if session.recording_path is None:
            return None
        last = session.pipeline.imu.tail(1)
        return session.recording_path, float(last[0][0]) if len(last) else 0.0

    def _adopt(self, session: LiveSession) -> None:
        self.session = session
        self.live_view.set_session(session)
        self.replay_bar.set_session(session)
        self.estimator_panel.set_session(session, self.live_view.attitude.visible_labels())
        self.uplink_panel.set_session(session)
        self.bar.set_connected(True)

    def disconnect(self) -> None:
        if self.seeking is not None:
            self.seeking.cancel()
            self.seeking = None
        if self.session is not None:
            description = self.session.source.description
            self._stop_session()
            self.source_label.setText(f"stopped: {description}")
        self.replay_bar.set_session(None)
        self.estimator_panel.set_session(None, set())
        self.uplink_panel.set_session(None)
        self.bar.set_connected(False)

    def _stop_session(self) -> None:
        session, self.session = self.session, None
        session.stop()
        self.last_file = self._session_file(session)
        if not hasattr(session.source, "recording"):  # a replay's settings are the recording's, not the user's
            tuned = session.pipeline.settings()
            self.settings.setValue("estimator_settings", json.dumps(
                {name: {k: tuned[name][k] for k, _, _ in fields} for name, fields in TUNABLE.items() if name in tuned}))

    def show_error(self, message: str | None) -> None:
        self.banner.setText(message or "")
        self.banner.setVisible(bool(message))

    # -- the redraw timer -----------------------------------------------------------------------

    def tick(self) -> None:
        if self.seeking is not None:
            if not self.seeking.done:
                self.replay_bar.position.setText(f"seeking… {100 * self.seeking.fraction:.0f} %")
                return
            self._adopt(self.seeking.session.start())
            self.seeking = None
        session = self.session
        self.ticks += 1
        figures = self.ticks % FIGURES_EVERY == 0
        if figures:
            self.link_panel.refresh(session)
        if session is None:
            return
        self.live_view.refresh()
        if self.ticks % HORIZON_EVERY == 0:
            self.attitude_panel.show_session(session)
        if figures:
            self.replay_bar.refresh()
            self.uplink_panel.refresh()
            self.estimator_panel.sync_shown(self.live_view.attitude.visible_labels())
            self.recording_label.setText(self._recording_text(session))
        if session.error and not self.banner.isVisible():
            self.show_error(f"The session stopped: {session.error}")

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

    def _stored_hidden_curves(self) -> frozenset[str]:
        hidden = self._stored_labels("hidden_curves")
        if hidden is None:
            return DEFAULT_HIDDEN
        return hidden | (DEFAULT_HIDDEN - self._known_curves())  # estimators added since then start hidden too

    def _stored_labels(self, key: str) -> frozenset[str] | None:
        stored = self.settings.value(key)
        if stored is None:
            return None
        return frozenset([stored] if isinstance(stored, str) else stored)  # QSettings gives one item as a str

    def _known_curves(self) -> frozenset[str]:
        """The legend labels the stored "hidden_curves" has decided on."""
        known = self._stored_labels("known_curves")
        return FORMERLY_KNOWN if known is None else known

    def _stored_estimator_settings(self) -> dict | None:
        """The tuned settings of the last live session (QSettings), for the next one."""
        stored = self.settings.value("estimator_settings")
        try:
            return json.loads(stored) if stored else None
        except ValueError:
            return None  # a damaged settings file must not keep the app from starting

    def _restore_layout(self) -> None:
        for key, restore in (("geometry", self.restoreGeometry), ("splitter", self.splitter.restoreState)):
            value = self.settings.value(key)
            if value is not None:
                restore(value)

    def closeEvent(self, event) -> None:
        self.disconnect()
        # "" for none: QSettings reads an empty list back as None, which means "the defaults"
        self.settings.setValue("hidden_curves", sorted(self.live_view.hidden_labels()) or "")
        known = {spec.label for spec, _ in self.live_view.attitude.curves} | self._known_curves()
        self.settings.setValue("known_curves", sorted(known))
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("splitter", self.splitter.saveState())
        self.settings.sync()
        super().closeEvent(event)

"""The main window: connection bar, live view, side panels, status bar; owns the current session.

One ``QTimer`` (``REDRAW_HZ``) pulls from the session's tables and redraws; the session's reader
thread never touches a widget. A file (a recording, a dataset CSV, a .tlog, .bin or .ulg) is computed
whole in a worker thread, its progress under the connection bar, then played back by revealing it
(``session.playback``): seeking only moves the playback clock. Problems (a busy port, an unreadable
file, a lost port) appear in the red banner under the connection bar, never as a traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

from PySide6 import QtCore, QtGui, QtWidgets

from groundstation.errors import UserError
from groundstation import formats
from groundstation.estimation import ESTIMATORS, label
from groundstation.estimation.warm_up import stop_warm_up
from groundstation.recording import default_recordings_dir
from groundstation.session.playback import RevealSession
from groundstation.session.view import Session
from groundstation.sources import whole_file
from groundstation.sources.sniff import as_mavlink
from groundstation.ui.about import show_about
from groundstation.ui.attitude_indicator import AttitudePanel
from groundstation.ui.carried_over import carried_over_note
from groundstation.ui.connection_bar import ConnectionBar
from groundstation.ui.estimator_panel import EstimatorPanel
from groundstation.ui.event_console import EventConsole
from groundstation.ui.parameters_view import ParametersView
from groundstation.ui.export_dialog import ExportDialog
from groundstation.ui.foxglove_switch import FoxgloveSwitch
from groundstation.ui.gui_collector import collect_in_gui_thread
from groundstation.ui.link_panel import LinkPanel
from groundstation.ui.live_view import LiveView
from groundstation.ui.config_banner import ConfigBanner
from groundstation.ui.recording_banner import RecordingBanner
from groundstation.ui.replay_bar import ReplayBar
from groundstation.ui.session_list import SessionList
from groundstation.ui.uplink_panel import UplinkPanel
from groundstation.ui.vehicle_badge import VehicleBadge
from groundstation.ui.whole_flight import opening_playback
from groundstation.ui.elided_label import ElidedLabel
from groundstation.ui.steady_layout import BannerOverlay, ReservedStrip

REDRAW_HZ = 30
# Every how many ticks the side panels redraw: the horizon at 15 Hz, the 3D view (its paint costs
# several times the horizon's), figures and labels at 5 Hz (each repaint costs CPU under software
# rendering; people read numbers no faster).
HORIZON_EVERY, BODY_EVERY, FIGURES_EVERY = 2, 6, 6
# The comparison estimators start switched off: shown are the best (AHF2, on the BROAD dev set,
# bench/bench_estimators.out.md), the paper's AHF and the aircraft's own estimate.
# The paper's AHF is one click away, not a noise band over every first view (issue 34): the aiding
# estimator and the aircraft's own estimate are what a first look needs.
SHOWN_AT_FIRST = ("ahf2",)
STEP_S = 5.0  # ← and → in a replay
PAN_FRACTION = 0.1  # of the window, ← and → live
RECENT_RECORDINGS = 8  # listed in File > Recent recordings
RECENT_SOURCES = 8  # listed in the source box below the ports found
# The curves of the versions that stored "hidden_curves" without "known_curves": any other label is new
# to the user's settings and starts hidden if it is in default_hidden().
FORMERLY_KNOWN = frozenset({"AHF", "onboard", "HF", "ECF"})


def default_hidden() -> frozenset[str]:
    """The legend labels of the estimators that start switched off."""
    return frozenset(label(name) for name in ESTIMATORS if name not in SHOWN_AT_FIRST)


class MainWindow(QtWidgets.QMainWindow):
    """``sessions``: how sessions are opened (``session_makers.factory.Sessions``): handed in, so that the
    window reads sessions (``session.view``) and imports nothing that makes them."""

    def __init__(self, settings: QtCore.QSettings, sessions, recordings_dir: Path | None = None):
        super().__init__()
        collect_in_gui_thread()  # never in a loading thread: ui/gui_collector.py
        self.setWindowTitle("groundstation")
        self.settings = settings
        self.sessions = sessions
        self.recordings_dir = recordings_dir
        self.session: Session | None = None
        self.loading = None  # a file being computed (``sessions.load``)
        self.compiling = None  # the process compiling estimators the file shown was computed without (``Loading.warm_up``)
        self._recomputing = False  # the loading is a what-if of the session shown: it keeps the position
        self.last_file: tuple[Path, float] | None = None  # the last session's recording and its length (s)
        self.typed_source: str | None = None  # the source string of the live session shown (Connect)
        self.bar = ConnectionBar()
        self.bar.set_recent(self.recent_sources())
        # Offered until something streams; from then on the box shows what streams (``_start``).
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
        self.recording_banner = RecordingBanner()
        self.config_banner = ConfigBanner()
        self.replay_bar = ReplayBar()
        self.replay_bar.seekRequested.connect(self.seek)
        self.replay_bar.hide()
        self.loading_bar = QtWidgets.QProgressBar(maximum=1000)
        self.loading_cancel = QtWidgets.QPushButton("Cancel")
        self.loading_cancel.clicked.connect(self.cancel_loading)
        self.loading_row = QtWidgets.QWidget()
        loading_layout = QtWidgets.QHBoxLayout(self.loading_row)
        loading_layout.setContentsMargins(4, 0, 4, 0)
        loading_layout.addWidget(self.loading_bar, 1)
        loading_layout.addWidget(self.loading_cancel)
        self.loading_row.hide()
        self.live_view = LiveView(self._stored_hidden_curves())
        self.live_view.channels.use_settings(settings)
        self.live_view.window_box.setCurrentText(str(settings.value("time_window", self.live_view.window_box.currentText())))
        self.link_panel = LinkPanel()
        self.attitude_panel = AttitudePanel()
        self.estimator_panel = EstimatorPanel()
        self.estimator_panel.visibilityChanged.connect(self.live_view.set_visible)
        self.estimator_panel.replayAsked.connect(self.rerun_replay)
        self.uplink_panel = UplinkPanel()
        self.estimator_panel.sendToAircraft.connect(self.uplink_panel.send_ahf)
        controls = QtWidgets.QTabWidget()
        controls.addTab(self.estimator_panel, "Estimators")
        controls.addTab(self.uplink_panel, "Uplink")
        self.event_console = EventConsole()
        self.event_console.timeRequested.connect(self.live_view.show_time)
        controls.addTab(self.event_console, "Events")
        self.parameters_view = ParametersView()
        controls.addTab(self.parameters_view, "Parameters")
        self.controls = controls
        side = QtWidgets.QWidget()
        side_layout = QtWidgets.QVBoxLayout(side)
        side_layout.setContentsMargins(0, 0, 0, 0)
        side_layout.addWidget(self.attitude_panel)
        side_layout.addWidget(self.link_panel)
        side_layout.addWidget(controls, 1)
        self.splitter = QtWidgets.QSplitter()
        self.splitter.addWidget(self.live_view)
        scroll = QtWidgets.QScrollArea()  # the panels are taller than a laptop's screen allows
        scroll.setWidget(side)
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        scroll.setMinimumWidth(side.minimumSizeHint().width() + scroll.verticalScrollBar().sizeHint().width())
        scroll.setFrameShape(QtWidgets.QFrame.NoFrame)
        self.splitter.addWidget(scroll)
        self.splitter.setStretchFactor(0, 1)
        central = QtWidgets.QWidget()
        # A click anywhere that takes no focus itself (a tab, a panel, the background) takes it from a
        # text field, so that Space, the arrows, Home and End are the window's again (issue 24, defect 2).
        central.setFocusPolicy(QtCore.Qt.ClickFocus)
        layout = QtWidgets.QVBoxLayout(central)
        layout.setContentsMargins(4, 0, 4, 0)
        layout.addWidget(self.bar)
        # One row always in use: the time window and the pause, then the replay bar or the progress of a file in a
        # strip that keeps its height whether or not they show; the plots never move (ui/steady_layout.py).
        view_row = QtWidgets.QHBoxLayout()
        view_row.addWidget(self.live_view.view_controls)
        view_row.addWidget(ReservedStrip(self.replay_bar, self.loading_row), 1)
        layout.addLayout(view_row)
        layout.addWidget(self.splitter, 1)
        BannerOverlay(self.splitter, (self.banner, self.recording_banner, self.config_banner))
        self.setCentralWidget(central)
        self.source_label = ElidedLabel("no source")  # a long path cut in the middle, whole in the tooltip
        self.recording_label = ElidedLabel("not recording")
        self.statusBar().addWidget(self.source_label, 1)
        self.vehicle_badge = VehicleBadge()  # an autopilot's mode and arming, always in sight
        self.statusBar().addPermanentWidget(self.vehicle_badge)
        self.compiling_label = QtWidgets.QLabel()  # a first start: "compiling estimators: N left", then gone
        self.compiling_label.hide()
        self.statusBar().addPermanentWidget(self.compiling_label)
        self.statusBar().addPermanentWidget(self.recording_label)
        self.record_action = QtGui.QAction("Start recording", self, shortcut=QtGui.QKeySequence("Ctrl+R"))
        self.record_action.setShortcutContext(QtCore.Qt.ApplicationShortcut)
        self.record_action.setToolTip("Start or stop recording the live source into a new file (replays are not re-recorded)")
        self.record_action.triggered.connect(lambda _=False: self.toggle_recording())
        record_button = QtWidgets.QToolButton()
        record_button.setDefaultAction(self.record_action)
        self.statusBar().addPermanentWidget(record_button)
        self.foxglove_label = QtWidgets.QLabel("")
        self.statusBar().addPermanentWidget(self.foxglove_label)
        self.foxglove = FoxgloveSwitch(settings, self.foxglove_label.setText, self.show_error, self)
        self.session_list = SessionList(self)  # sessions beside this one (``ui.session_list``): in the side tabs
        self.controls.addTab(self.session_list, "Sessions")
        # The Estimators panel tunes the session selected there (``_tune_selected``), its box selecting there too.
        self.session_list.selectionChanged.connect(self._tune_selected)
        self.session_list.changed.connect(self._tune_selected)
        self.estimator_panel.sessionChosen.connect(self.session_list.select_row)
        self.estimator_panel.otherShown.connect(
            lambda name, on: self.session_list.show_estimator(self.session_list.selected(), name, on))
        self._tune_selected()
        self._build_menus()
        self._sync_record_action()
        self.resize(1280, 800)
        self._restore_layout()
        self.ticks = 0
        self.timer = QtCore.QTimer(self, interval=1000 // REDRAW_HZ, timeout=self.tick)
        self.timer.start()

    # -- sessions -------------------------------------------------------------------------------

    def start_demo(self, note: str = "") -> None:
        self._start(self.sessions.demo_spec, lambda: self.sessions.open(
            self.sessions.demo_spec, settings=self._stored_estimator_settings(), recordings_dir=self.recordings_dir).start(), note)

    def connect_serial(self, port: str, baud: int = 0, note: str = "") -> None:
        """Connect to ``port``: any source string ``open_source`` accepts (a bad one is explained in the
        banner), at ``baud`` if it is a serial port (0: the source's default); a file typed there (a
        recording, ``mavlink:FILE.tlog``, a flight log) is opened whole."""
        file = whole_file(port)
        if file is not None:
            self.open_recording(file)
            return
        self.settings.setValue("port", port)
        self.settings.setValue("baud", baud)
        rate = {"baud": baud} if baud else {}
        self._start(port, lambda: self.sessions.open(port, settings=self._stored_estimator_settings(),
                                                     recordings_dir=self.recordings_dir, **rate).start(), note)
        self.typed_source = port if self.session is not None else None
        if self.session is not None:
            recent = [port, *(s for s in self.recent_sources() if s != port)][:RECENT_SOURCES]
            self.settings.setValue("recent_sources", recent)
            self.bar.set_recent(recent)

    def recent_sources(self) -> list[str]:
        return self._stored_list("recent_sources")

    def _stored_list(self, key: str) -> list[str]:
        stored = self.settings.value(key) or []
        return [stored] if isinstance(stored, str) else list(stored)  # QSettings gives one item as a str

    def open_recording(self, path) -> None:
        """Open a file whole: a recording (its recorded estimators), a dataset CSV or a flight log (the
        app's estimators); computed in a worker, then played from the start (``tick`` adopts it)."""
        self.disconnect()
        path = Path(path)
        self._load(path, None, None, f"computing {path.name}")  # the estimators: ``load.estimators_for``

    def _load(self, path: Path, filters, forced, text: str, recompute: bool = False) -> None:
        if self.loading is not None:
            self.loading.cancel()
        self.show_error(None)
        self.loading = self.sessions.load(path, filters, forced)
        self._recomputing = recompute
        self.loading_bar.setFormat(f"{text}… %p %")
        self.loading_bar.setValue(0)
        self.loading_row.show()

    def cancel_loading(self) -> None:
        if self.loading is not None:
            self.loading.cancel()
            self.loading = None
        self.loading_row.hide()

    def _loaded(self) -> None:
        """The file is computed: play it (from where the session shown was, for a what-if), or say why not."""
        loading, self.loading = self.loading, None
        self.loading_row.hide()
        if loading.error is not None:
            self.show_error(loading.error)
            return
        shown = self.session if self._recomputing and self.session is not None and self.session.seekable else None
        if shown is not None:
            shown.advance()
            playback = {"paused": shown.source.paused, "position_s": shown.source.position_s}
            self._stop_session()
        else:
            playback = opening_playback(loading.path)  # a flight log whole, at its end (``whole_flight``)
        self._adopt(RevealSession(loading.data, loading.path, loading.setup, speed=self.replay_bar.speed,
                                  uncompiled=loading.pending, **playback))
        self.compiling = loading.warm_up
        self.source_label.setText(self.session.source.description)
        if shown is None:
            self._remember_recent(loading.path.resolve())

    def recording_dialog(self) -> QtWidgets.QFileDialog:
        """A file dialog in the folder live sessions record to, where yesterday's flight is."""
        folder = self.recordings_dir or default_recordings_dir()
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError:
            pass  # the dialog then starts where it can
        dialog = QtWidgets.QFileDialog(self, "Open recording or flight log", str(folder), formats.dialog_filter())
        dialog.setFileMode(QtWidgets.QFileDialog.ExistingFile)
        return dialog

    def choose_recording(self) -> None:
        dialog = self.recording_dialog()
        if dialog.exec() and dialog.selectedFiles():
            self.open_recording(dialog.selectedFiles()[0])

    def recent_recordings(self) -> list[str]:
        return self._stored_list("recent_recordings")

    def _remember_recent(self, path: Path) -> None:
        recent = [str(path), *(p for p in self.recent_recordings() if p != str(path))][:RECENT_RECORDINGS]
        self.settings.setValue("recent_recordings", recent)
        self._fill_recent_menu()

    def _fill_recent_menu(self) -> None:
        self.recent_menu.clear()
        for path in self.recent_recordings():
            action = self.recent_menu.addAction(f"{Path(path).parent.name}/{Path(path).name}")
            action.setData(path)
            action.setToolTip(path)
            action.triggered.connect(lambda _=False, p=path: self.open_recording(p))
        self.recent_menu.setEnabled(bool(self.recent_menu.actions()))

    def seek(self, t_s: float) -> None:
        """Move the replay's clock to ``t_s`` (nothing is recomputed); its pause and speed stay. Back in
        time, the views that only ever add rows start over."""
        session = self.session
        if session is not None and session.seek(t_s):
            self.live_view.set_session(session)
            self.event_console.set_session(session)
            # and the clock counts from now: the views' restart (a second for a whole flight on a busy machine) is
            # no playback time ("Replay" at 8x began 8 s in)
            session.seek(t_s)

    def rerun_replay(self, filters: tuple[str, ...], forced: dict) -> None:
        """The what-if: the file computed again with ``filters`` and ``forced`` settings, in a worker;
        the replay goes on meanwhile and continues from where it is. An added file (the Estimators panel
        tuning it): that file only (``SessionList.recompute``)."""
        added = self.session_list.selected()
        if added is not None:
            self.session_list.recompute(added, filters, forced)
            return
        session = self.session
        if session is not None and session.seekable:
            self._load(session.source.path, tuple(filters), forced, f"recomputing {session.source.path.name} with "
                       f"{', '.join(filters)}", recompute=True)

    def _start(self, spec: str, start, note: str = "") -> None:
        """Stop the current session, then start another on ``spec``; a failure leaves none and says why.
        The Source box shows ``spec`` once it streams, so it never names another source than the plots'."""
        self.disconnect()
        try:
            session = start()
        except UserError as error:
            self.show_error(str(error))
            return
        self.show_error(None)
        self._adopt(session)
        self.bar.select(spec, None)
        notes = [note, "" if session.source.is_replay else carried_over_note(self._stored_estimator_settings())]
        self.source_label.setText("  —  ".join([session.source.description, *filter(None, notes)]))

    def export(self) -> ExportDialog | None:
        """The export dialog on the current session's file (or the last one's), with the estimators shown."""
        file = self.session.file() if self.session is not None else self.last_file
        if file is None:
            self.show_error("Nothing to export yet: connect, start the simulated bridge or open a recording first.")
            return None
        return self.export_file(file, self.session.setup if self.session is not None else (None, None))

    def export_file(self, file: tuple[Path, float], setup: tuple) -> ExportDialog:
        """The export dialog on ``file`` (path, length in s) computed with ``setup``."""
        dialog = ExportDialog(self.sessions.load_session, *file, parent=self, setup=setup, settings=self.settings)
        dialog.setModal(False)  # the live view goes on while it exports
        dialog.show()
        return dialog

    def flight_report(self, out: Path | None = None):
        """File > Flight report…: the session's file (or the last one's) as an HTML report, written in
        the background; the status bar says where (the banner, why not). ``out``: skip the file dialog."""
        from groundstation.ui.report_job import ReportJob

        file = self.session.file() if self.session is not None else self.last_file
        if file is None:
            self.show_error("Nothing to report on yet: open a recording or flight log, or connect first.")
            return None
        source = Path(file[0])
        if out is None:
            chosen, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Flight report", str(source.with_suffix(".html")), "HTML page (*.html)")
            if not chosen:
                return None
            out = Path(chosen)
        setup = self.session.setup if self.session is not None else (None, None)
        try:
            job = self.report_job = ReportJob(self.sessions.load_session, source, out, setup).start()
        except UserError as error:
            self.show_error(str(error))
            return None
        self.statusBar().showMessage(f"writing the flight report of {source.name}…")
        timer = QtCore.QTimer(self, interval=200)

        def check() -> None:
            if job.done:
                timer.stop()
                self.show_error(job.error)
                self.statusBar().showMessage(job.message or "")

        timer.timeout.connect(check)
        timer.start()
        return job

    def _adopt(self, session: Session) -> None:
        self.session = session
        self.statusBar().clearMessage()  # a message about the last session (a report written) hid this one's name
        self.attitude_panel.clear()  # nothing of the previous session's attitude
        self.live_view.set_session(session)
        self.replay_bar.set_session(session)
        self._tune_selected()
        self.uplink_panel.set_session(session)
        self.event_console.set_session(session)
        self.parameters_view.set_session(session)
        self.link_panel.refresh(session)
        self.bar.set_connected(True, getattr(session.source, "path", None) if session.source.is_replay else None)
        self.centralWidget().setFocus()  # out of the source box: the keys control the view
        self._sync_record_action()
        self.foxglove.follow(session)
        self.session_list.primary_changed()

    def disconnect(self) -> None:
        self.cancel_loading()
        self.typed_source = None
        self.attitude_panel.clear()  # no attitude of a stopped session stands
        if self.session is not None:
            description = self.session.source.description
            self._stop_session()
            self.source_label.setText(f"stopped: {description}")
            self.recording_label.setText("not recording")
        self.replay_bar.set_session(None)
        self._tune_selected()
        self.uplink_panel.set_session(None)
        self.bar.set_connected(False)
        self._sync_record_action()

    def _stop_session(self) -> None:
        session, self.session = self.session, None
        self.foxglove.follow(None)
        self.session_list.primary_changed()
        session.stop()
        self.last_file = session.file()
        if not session.source.is_replay:  # a replay's settings are the recording's, not the user's
            tuned = session.view.settings()
            self.settings.setValue("estimator_settings", json.dumps(
                {name: {k: tuned[name][k] for k, _, _ in fields} for name, fields in self.estimator_panel.tunable.items()
                 if name in tuned}))

    def _tune_selected(self) -> None:
        """The Estimators panel on the session selected in the Sessions tab (the window's own at first),
        filled anew only when that session is another: fields being typed into stay as they are."""
        label, session = self.session_list.tuned()
        self.estimator_panel.set_choices(self.session_list.names(), self.session_list.selected_row())
        if session is not self.estimator_panel.session or label != self.estimator_panel.label:
            self.estimator_panel.set_session(session, self.live_view.attitude.visible_labels(), label)

    def show_error(self, message: str | None) -> None:
        self.banner.setText(message or "")
        self.banner.setVisible(bool(message))

    # -- menus and keys -------------------------------------------------------------------------

    def _build_menus(self) -> None:
        """File and View menus whose actions carry the keyboard shortcuts, and Help listing them."""
        file = self.menuBar().addMenu("&File")
        self._action(file, "&Open recording or flight log…", "Ctrl+O", self.choose_recording)
        self.recent_menu = file.addMenu("Recent recordings")
        self._fill_recent_menu()
        self._action(file, "&Export…", "Ctrl+E", self.export)
        file.addSeparator()
        self._action(file, "Add source beside…", "Ctrl+Shift+N", self.session_list.ask_source)
        file.addAction("Add file beside…").triggered.connect(lambda _=False: self.session_list.ask_file())
        file.addSeparator()
        self.fast_imu_action = file.addAction("Full-rate IMU for flight logs (ISBD, sensor_gyro_fifo)")
        self.fast_imu_action.setCheckable(True)
        self.fast_imu_action.setChecked(self.sessions.imu == "fast")
        self.fast_imu_action.toggled.connect(self.use_fast_imu)
        self._action(file, "Flight &report…", "Ctrl+Shift+R", self.flight_report)
        file.addAction(self.record_action)
        file.addAction(self.foxglove.action)
        file.addAction("Foxglove port…").triggered.connect(lambda _=False: self.foxglove.choose_port())
        file.addSeparator()
        self._action(file, "&Quit", "Ctrl+Q", self.close)
        view = self.menuBar().addMenu("&View")
        self._action(view, "Pause / resume (playback in a replay, the view when live)", "Space", self.pause_or_resume)
        self._action(view, "Back (5 s in a replay; live: pan the paused view)", "Left", lambda: self.step_time(-1))
        self._action(view, "Forward", "Right", lambda: self.step_time(+1))
        self._action(view, "To the start", "Home", lambda: self.to_end(False))
        self._action(view, "To the end (live: follow the newest data)", "End", lambda: self.to_end(True))
        help_menu = self.menuBar().addMenu("&Help")
        self._action(help_menu, "&Keyboard shortcuts", "F1", self.show_shortcuts)
        help_menu.addAction("&About groundstation").triggered.connect(lambda _=False: show_about(self))

    def use_fast_imu(self, fast: bool) -> None:
        """Run a flight log's estimators on its full-rate IMU (or its logged one): the open file again."""
        self.sessions.imu = "fast" if fast else "regular"
        if self.session is not None and self.session.seekable:  # a file played, not a live link
            self.open_recording(self.session.file()[0])

    def _action(self, menu: QtWidgets.QMenu, text: str, key: str, slot) -> QtGui.QAction:
        action = menu.addAction(text)
        action.setShortcut(QtGui.QKeySequence(key))
        action.setShortcutContext(QtCore.Qt.ApplicationShortcut)  # also while a panel's field has the focus
        action.triggered.connect(lambda _=False: slot())
        return action

    def shortcuts(self) -> list[tuple[str, str]]:
        """(key, what it does) of every menu action that has a key."""
        return [(a.shortcut().toString(QtGui.QKeySequence.NativeText), a.text().replace("&", ""))
                for menu in self.menuBar().findChildren(QtWidgets.QMenu) for a in menu.actions() if not a.shortcut().isEmpty()]

    def show_shortcuts(self) -> QtWidgets.QMessageBox:
        rows = "".join(f"<tr><td><b>{key}</b></td><td>{text}</td></tr>" for key, text in self.shortcuts())
        box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Information, "Keyboard shortcuts", f"<table>{rows}</table>",
                                    QtWidgets.QMessageBox.Close, self)
        box.setModal(False)
        box.show()
        return box

    def pause_or_resume(self) -> None:
        if self.replay_bar.session is not None:
            self.replay_bar.toggle()
        else:
            self.live_view.pause_button.toggle()

    def step_time(self, direction: int) -> None:
        if self.replay_bar.session is not None:
            self.seek(max(self.replay_bar.source.position_s + direction * STEP_S, 0.0))
        else:
            self.live_view.pan(direction * PAN_FRACTION)

    def to_end(self, end: bool) -> None:
        if self.replay_bar.session is not None:
            self.seek(self.replay_bar.source.duration_s if end else 0.0)
        elif end:
            self.live_view.pause_button.setChecked(False)
        else:
            self.live_view.show_time(None)

    # -- the redraw timer -----------------------------------------------------------------------

    def tick(self) -> None:
        if self.loading is not None:
            self.loading_bar.setValue(int(1000 * self.loading.fraction))
            if self.loading.done:
                self._loaded()
        session = self.session
        if session is not None:
            session.advance()
        self.session_list.tick()  # the sessions beside it: played along, placed on its time axis
        self.ticks += 1
        figures = self.ticks % FIGURES_EVERY == 0
        if figures:
            self.link_panel.refresh(session)
            self.vehicle_badge.refresh(self.live_view.mode_bands.spans if session is not None else [])
            self.recording_banner.refresh(session)
            self.config_banner.refresh(session)
            self._follow_compiling(session)
        if session is None:
            return
        self.live_view.refresh()
        if self.ticks % HORIZON_EVERY == 0:
            self.attitude_panel.show_session(session, body=self.ticks % BODY_EVERY == 0)
        if figures:
            self.replay_bar.refresh()
            self.uplink_panel.refresh()
            self.event_console.refresh()
            self.parameters_view.refresh()
            self.estimator_panel.sync_shown(self.live_view.attitude.visible_labels())
            self.recording_label.setText(self._recording_text(session))
            self._sync_record_action()
            self._follow_mavlink(session)
        if session.error and not self.banner.isVisible():
            self.show_error(f"The session stopped: {session.error}")

    def _follow_compiling(self, session: Session | None) -> None:
        """While estimators' kernels compile in the background (a first start), the status bar counts them and
        the Estimators panel marks them; a file's join its plots as they are ready: the file computed
        again (``rerun_replay``'s way), from where it is shown."""
        left = session.view.uncompiled() if session is not None else ()
        self.compiling_label.setText(f"compiling estimators: {len(left)} left" if left else "")
        self.compiling_label.setVisible(bool(left))
        self.estimator_panel.mark_uncompiled(left)
        warm = self.compiling
        if not left or warm is None or self.loading is not None or not session.seekable:
            return
        ready = [name for name in left if name in warm.runs]
        if ready:
            self._load(session.source.path, *session.setup, f"adding {', '.join(label(name) for name in ready)} to "
                       f"{session.source.path.name}", recompute=True)
        elif warm.finished:  # it stopped without them: the file stays without them
            self.compiling = None

    def _follow_mavlink(self, session: Session) -> None:
        """An autopilot's MAVLink heard on a source opened for the project's bridge (QGroundControl's habit:
        udp://0.0.0.0:14550): the same port opened as ``mavlink:``, or the banner says how (issue 24, defect 4)."""
        if session.heard_protocol != "mavlink" or self.typed_source is None:
            return
        typed, self.typed_source = self.typed_source, None  # once
        spec = as_mavlink(typed, getattr(session.source, "baud", None))  # a port: udp, tcp or serial
        self.bar.port_box.setEditText(spec)
        self.connect_serial(spec, self.bar.baud, note=f"MAVLink heard on {typed}: opened as {spec}")

    @staticmethod
    def _recording_text(session: Session) -> str:
        if session.recorder is None:
            return "not recording (replay)"
        if session.recorder.state == "failed":
            return "⚠ NOT RECORDING (see the red banner)"
        path = session.recording_path
        if path is None:
            return "not recording"
        doing = "● recording" if session.recorder.state == "recording" else "not recording; last file"
        return f"{doing} {path}  ({session.recorder.bytes_written / 1e6:.1f} MB)"

    # -- recording ------------------------------------------------------------------------------

    def toggle_recording(self) -> None:
        """Stop the live session's recording, or start a new file; replays are not re-recorded."""
        session = self.session
        if session is None or session.source.is_replay:
            return
        if session.recorder.state == "recording":
            with session.lock:  # the reader thread writes under it
                session.recorder.stop()
        elif session.resume_recording() and session.source.can_send:
            session.send_command("request_config")  # a new file needs a CONFIG frame of its own to replay
        self.recording_banner.refresh(session)  # a file that cannot be made is explained there
        self.recording_label.setText(self._recording_text(session))
        self._sync_record_action()

    def _sync_record_action(self) -> None:
        session = self.session
        live = session is not None and not session.source.is_replay
        self.record_action.setEnabled(live)
        self.record_action.setText("Stop recording" if live and session.recorder.state == "recording" else "Start recording")

    # -- settings -------------------------------------------------------------------------------

    def _stored_hidden_curves(self) -> frozenset[str]:
        hidden = self._stored_labels("hidden_curves")
        default = default_hidden()
        if hidden is None:
            return default
        return hidden | (default - self._known_curves())  # estimators added since then start hidden too

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
        stop_warm_up()  # at once: what it compiled stays in numba's cache, the rest compiles at the next start
        self.disconnect()
        self.session_list.stop_all()
        # "" for none: QSettings reads an empty list back as None, which means "the defaults"
        self.settings.setValue("hidden_curves", sorted(self.live_view.hidden_labels()) or "")
        known = {spec.label for spec, _ in self.live_view.attitude.curves} | self._known_curves()
        self.settings.setValue("known_curves", sorted(known))
        self.settings.setValue("geometry", self.saveGeometry())
        self.settings.setValue("splitter", self.splitter.saveState())
        self.settings.setValue("channel_panes", self.live_view.channels.layout_json())
        self.settings.setValue("time_window", self.live_view.chosen_window)
        self.settings.sync()
        super().closeEvent(event)

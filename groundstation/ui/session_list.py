"""Sessions beside the window's own: a class of boards, or a board beside yesterday's recording, in one window.

The window's own session (the one its connection bar, tabs and panels show) is listed first as "main";
each session added here (File > Add source beside…, Add file beside…, or this panel's buttons) is
"S2", "S3", … and has its own tables, estimators and, when live, its own recording (as any live session
of the window). Its channels are listed under its name in the Channels tab ("S2:imu.acc_x_g") and can be
plotted in the panes with the window's, and named in custom series ("S2:imu.acc_x_g - imu.acc_x_g"); its
first estimator's (and any other shown in the Estimators panel) and its onboard pitch, roll and heading
join the Attitude and Heading tabs in a pen style of its own ("S2 AHF2", dotted). All are drawn on the window's time axis
(``session.timeline``: live sessions on wall time; a file from its start, played along with the window's
session). Each can be served to Foxglove on a port of its own (a taken one: the next free), exported, and
removed (stopped: its recording closed). The panel says each one's source, place on the axis and state.
The session selected here is the one the Estimators panel tunes (``tuned``; the panel's own box selects
here too): a live one's settings changed as the window's are, a file's computed again (``recompute``).
"""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtWidgets

from groundstation.errors import UserError
from groundstation.session.playback import RevealSession
from groundstation.session.timeline import offset_s, reveal_along
from groundstation.session.view import Session
from groundstation.sources import whole_file
from groundstation.ui.foxglove_switch import FoxgloveSwitch
from groundstation.ui.session_series import SESSION_STYLES, Other

REFRESH_EVERY = 6  # ticks of the window's timer between refreshes of the rows (5 Hz)
COLUMNS = ("session", "source", "on the time axis", "state", "Foxglove")


class Entry:
    """A session added beside the window's: being computed (``loading``, a file), then ``session``."""

    def __init__(self, label: str, style: str, what: str, window, parent):
        self.label = label
        self.style = style
        self.what = what  # the source spec or the file's name, until the session describes itself
        self.session = None
        self.loading = None
        self.offset_s: float | None = None  # None until placed on the window's axis
        self.foxglove_text = ""  # its bridge's address and clients, in its row
        self.shown: tuple[str, ...] | None = None  # its estimators plotted (``shown_now``); None: its first
        # From the window's port on: one taken by the window or another session gives the next free one.
        self.foxglove = FoxgloveSwitch(window.settings, lambda text: setattr(self, "foxglove_text", text), window.show_error,
                                       parent, remember=False, port=window.foxglove.port, text=f"Serve {label} to Foxglove")

    def shown_now(self) -> tuple[str, ...]:
        """The estimators of its session plotted: its first at the start, as the window's own."""
        filters = self.session.view.filters
        return filters[:1] if self.shown is None else tuple(name for name in self.shown if name in filters)


class SessionList(QtWidgets.QWidget):
    """The panel, and the sessions it holds; ``window``: the main window, whose session is the first and
    whose redraw timer calls ``tick``."""

    changed = QtCore.Signal()  # a session was added, placed on the axis, computed again or removed
    selectionChanged = QtCore.Signal()  # another row selected: another session to tune

    def __init__(self, window):
        super().__init__()
        self.window = window
        self.entries: list[Entry] = []
        self._count = 1  # labels are never reused in a window: a removed S2's layout never plots a new one
        self._ticks = 0
        self.tree = QtWidgets.QTreeWidget()
        self.tree.setHeaderLabels(list(COLUMNS))
        self.tree.setRootIsDecorated(False)
        self.tree.setUniformRowHeights(True)
        for column in (0, 2):  # short: the name and the place on the axis; the source and state take the rest
            self.tree.header().setSectionResizeMode(column, QtWidgets.QHeaderView.ResizeToContents)
        self.tree.currentItemChanged.connect(lambda *_: (self._sync_buttons(), self.selectionChanged.emit()))
        self.buttons = {}
        grid = QtWidgets.QGridLayout()
        for index, (text, slot) in enumerate({
                "Add source…": self.ask_source, "Add file…": self.ask_file, "Export…": self.export_selected,
                "Foxglove on/off": self.toggle_foxglove, "Foxglove port…": self.choose_port, "Remove": self.remove_selected}.items()):
            button = QtWidgets.QPushButton(text)
            button.clicked.connect(lambda _=False, slot=slot: slot())
            grid.addWidget(button, index // 2, index % 2)
            self.buttons[text] = button
        note = QtWidgets.QLabel("Channels of added sessions are named by session in the Channels tab (S2:imu.…). "
                                "Live sessions share wall time; a file starts at the time axis' 0.", wordWrap=True)
        note.setStyleSheet("color:#555")
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.tree, 1)
        layout.addLayout(grid)
        layout.addWidget(note)
        self.refresh_rows()

    # -- adding and removing ----------------------------------------------------------------------

    def _new_entry(self, what: str) -> Entry:
        self._count += 1
        style = SESSION_STYLES[(self._count - 2) % len(SESSION_STYLES)]
        return Entry(f"S{self._count}", style, what, self.window, self)

    def add_source(self, spec: str) -> Entry | None:
        """A live source beside the window's session (a file named: ``add_file``); None, and the banner
        says why, when it cannot be opened."""
        file = whole_file(spec)
        if file is not None:
            return self.add_file(file)
        window = self.window
        try:
            session = window.sessions.open(spec, settings=window._stored_estimator_settings(),
                                           recordings_dir=window.recordings_dir).start()
        except UserError as error:
            window.show_error(str(error))
            return None
        window.show_error(None)  # an earlier refusal no longer stands
        entry = self._new_entry(spec)
        entry.session = session
        entry.foxglove.follow(session)
        self.entries.append(entry)
        self.publish()
        return entry

    def add_file(self, path) -> Entry:
        """A file beside the window's session: computed in a worker, then played along (``tick``)."""
        path = Path(path)
        entry = self._new_entry(path.name)
        entry.loading = self.window.sessions.load(path, compile_in_background=False)  # a file beside is not computed again
        self.entries.append(entry)
        self.refresh_rows()
        return entry

    def remove(self, entry: Entry) -> None:
        """Stop the session (its recording closed) and forget it."""
        entry.foxglove.action.setChecked(False)
        if entry.loading is not None:
            entry.loading.cancel()
        if entry.session is not None:
            entry.session.stop()
        self.entries.remove(entry)
        self.publish()

    def stop_all(self) -> None:
        for entry in list(self.entries):
            self.remove(entry)

    # -- the window's timer ---------------------------------------------------------------------

    def tick(self) -> None:
        """Files computed become sessions (or take the place of their earlier computation); each session
        placed on the window's axis once it can be; files revealed up to the window's present."""
        first = self.window.session
        moved = False
        for entry in list(self.entries):
            if entry.loading is not None and entry.loading.done:
                moved |= self._loaded(entry)
            if entry.session is None:
                continue
            if entry.session.seekable:
                moved |= reveal_along(first, entry.session)  # back in time: its series start over
            if entry.offset_s is None and first is not None:
                entry.offset_s = offset_s(first, entry.session)
                moved |= entry.offset_s is not None
        if moved:
            self.publish()
        self._ticks += 1
        if self._ticks % REFRESH_EVERY == 0:
            self.refresh_rows()

    def _loaded(self, entry: Entry) -> bool:
        loading, entry.loading = entry.loading, None
        if loading.error is not None:
            self.window.show_error(f"{entry.label}: {loading.error}")
            if entry.session is None:  # a file being added: nothing of it to keep (a what-if's file plays on)
                self.entries.remove(entry)
            self.refresh_rows()
            return False
        if entry.session is not None:  # computed again (``recompute``): the earlier computation gives way
            entry.session.stop()
        entry.session = RevealSession(loading.data, loading.path, loading.setup, paused=True)  # moved by ``reveal_along``
        entry.foxglove.follow(entry.session)
        return True

    def recompute(self, entry: Entry, filters: tuple[str, ...], forced: dict) -> None:
        """The what-if on an added file (the window's ``rerun_replay`` for its own): computed again with
        ``filters`` and ``forced`` settings in a worker, played along as it was meanwhile."""
        if entry.loading is not None:
            entry.loading.cancel()
        entry.loading = self.window.sessions.load(entry.session.source.path, tuple(filters), forced)
        self.refresh_rows()

    def show_estimator(self, entry: Entry, name: str, shown: bool) -> None:
        """Plot (or not) estimator ``name`` of an added session, beside its others shown."""
        now = entry.shown if entry.shown is not None else entry.session.view.filters[:1]
        entry.shown = (*now, name) if shown and name not in now else tuple(n for n in now if shown or n != name)
        self.publish()

    def primary_changed(self) -> None:
        """The window's own session changed (or stopped): every other is placed on its axis anew."""
        for entry in self.entries:
            entry.offset_s = None
        self.publish()

    def others(self) -> list[Other]:
        """The sessions placed on the window's axis (none without a window's session)."""
        if self.window.session is None:
            return []
        return [Other(e.label, e.session, e.offset_s, e.style, e.shown_now()) for e in self.entries
                if e.session is not None and e.offset_s is not None]

    def publish(self) -> None:
        self.window.live_view.set_others(self.others())
        self.refresh_rows()
        self.changed.emit()

    # -- the panel ------------------------------------------------------------------------------

    def refresh_rows(self) -> None:
        """One row for the window's session, one for each other: what it is, where it is, how it is."""
        window = self.window
        rows = [("main", window.session.source.description if window.session is not None else "none",
                 "its own axis" if window.session is not None else "",
                 self._state(window.session) if window.session is not None else "", window.foxglove_label.text()
                 if window.foxglove.action.isChecked() else "")]
        for entry in self.entries:
            session = entry.session
            where = ("" if session is None else "waiting for its first data" if entry.offset_s is None
                     else f"from {entry.offset_s:+.1f} s")
            state = f"computing {entry.loading.fraction:.0%}" if entry.loading is not None else self._state(session)
            rows.append((entry.label, session.source.description if session is not None else entry.what, where, state,
                         entry.foxglove_text if entry.foxglove.action.isChecked() else ""))
        labels = [row[0] for row in rows]
        if [self.tree.topLevelItem(i).text(0) for i in range(self.tree.topLevelItemCount())] != labels:
            selected = self.selected_label()  # kept by its name: rows come and go around it
            self.tree.blockSignals(True)  # no passing selection of the first row while the rows are made
            self.tree.clear()
            self.tree.addTopLevelItems([QtWidgets.QTreeWidgetItem(list(row)) for row in rows])
            self.tree.setCurrentItem(self.tree.topLevelItem(labels.index(selected) if selected in labels else 0))
            self.tree.blockSignals(False)
            if self.selected_label() != selected:  # the session selected was removed: the window's own now
                self.selectionChanged.emit()
        else:
            for index, row in enumerate(rows):
                item = self.tree.topLevelItem(index)
                for column, text in enumerate(row):
                    if item.text(column) != text:
                        item.setText(column, text)
                        item.setToolTip(column, text)
        self._sync_buttons()

    @staticmethod
    def _state(session) -> str:
        if session.error:
            return f"stopped: {session.error}"
        if session.seekable:
            return f"{session.source.position_s:.1f} of {session.source.duration_s:.1f} s"
        if not session.running:
            return "stopped"
        if not session.connected:
            return "reconnecting"
        recorder = session.recorder
        recording = (f"● recording {session.recording_path.name}" if recorder.state == "recording"
                     else "⚠ NOT RECORDING" if recorder.state == "failed" else "not recording")
        return f"{len(session.view.imu)} samples; {recording}"

    def selected(self) -> Entry | None:
        """The added session selected; None for the window's own (the first row)."""
        index = self.selected_row()
        return self.entries[index - 1] if index > 0 else None

    def selected_label(self) -> str:
        """"main" or the added session's name ("S2")."""
        return self.tree.currentItem().text(0) if self.tree.currentItem() else "main"

    def selected_row(self) -> int:
        return self.tree.indexOfTopLevelItem(self.tree.currentItem()) if self.tree.currentItem() else 0

    def select_row(self, row: int) -> None:
        """Select row ``row`` (0: the window's own session), as a click on it."""
        self.tree.setCurrentItem(self.tree.topLevelItem(row))

    def tuned(self) -> tuple[str, Session | None]:
        """The session selected, to tune: its name ("" for the window's own) and the session (None: none
        yet, or a file still being computed)."""
        entry = self.selected()
        return ("", self.window.session) if entry is None else (entry.label, entry.session)

    def names(self) -> list[str]:
        """Each row's session as the Estimators panel's box offers it: "main: sim:", "S2: sim:?seed=7"."""
        return [f"{item.text(0)}: {item.text(1)}" for item in
                (self.tree.topLevelItem(i) for i in range(self.tree.topLevelItemCount()))]

    def _sync_buttons(self) -> None:
        entry = self.selected()
        ready = entry is None and self.window.session is not None or entry is not None and entry.session is not None
        for text in ("Export…", "Foxglove on/off", "Foxglove port…"):
            self.buttons[text].setEnabled(ready)
        self.buttons["Remove"].setEnabled(entry is not None or self.window.session is not None)

    def ask_source(self) -> QtWidgets.QInputDialog:
        """A dialog asking the source to add (any the connection bar takes; a file is opened whole)."""
        dialog = QtWidgets.QInputDialog(self)
        dialog.setWindowTitle("Add a source beside the window's session")
        dialog.setLabelText("source: a port, socket://…, udp://…, sim:?seed=N, or a file")
        dialog.setComboBoxEditable(True)
        offered = [f"sim:?seed={self._count + 1}", *self.window.recent_sources()]  # another simulated board first
        dialog.setComboBoxItems(offered)
        dialog.setTextValue(offered[0])
        dialog.textValueSelected.connect(self.add_source)
        dialog.open()
        return dialog

    def ask_file(self) -> None:
        dialog = self.window.recording_dialog()
        if dialog.exec() and dialog.selectedFiles():
            self.add_file(dialog.selectedFiles()[0])

    def export_selected(self):
        """The export dialog on the selected session's file (its recording, for a live one)."""
        entry = self.selected()
        if entry is None:
            return self.window.export()
        file = entry.session.file() if entry.session is not None else None
        if file is None:
            self.window.show_error(f"{entry.label} has nothing to export: it is not recording")
            return None
        return self.window.export_file(file, entry.session.setup)

    def _switch(self) -> FoxgloveSwitch | None:
        entry = self.selected()
        return self.window.foxglove if entry is None else entry.foxglove if entry.session is not None else None

    def toggle_foxglove(self) -> None:
        switch = self._switch()
        if switch is not None:
            switch.action.toggle()
        self.refresh_rows()

    def choose_port(self) -> QtWidgets.QInputDialog | None:
        switch = self._switch()
        return switch.choose_port() if switch is not None else None

    def remove_selected(self) -> None:
        entry = self.selected()
        if entry is None:
            self.window.disconnect()
        else:
            self.remove(entry)

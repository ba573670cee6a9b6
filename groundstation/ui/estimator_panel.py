"""The estimator panel: show or hide the comparison estimators, tune the settings the estimators offer
(``Estimator.tunable``: AHF's λ bounds, HF's and HF+mag's β, ECF's and ECF+mag's Kp/Ki) live, back to
the defaults, or send AHF's λ bounds to the aircraft.

It acts on one session, named in its first row: the window's own ("main") or one added beside it ("S2"),
the one selected in the Sessions tab (its box selects there too). An added session's estimators shown
are plotted in its pen style ("S2 HF"); AHF's λ goes to the aircraft through the Uplink tab, which is
the window's own session's.

Live, a change goes through ``Session.change_settings``: it applies from the next sample, keeps
the attitude, and is written to the recording, so a replay changes it at the same point. In a replay
every estimator can be shown, those the file lacks too, and a change is a what-if (the CLI's
``--set``): the window computes the file again with the estimators and settings asked, and the
replay goes on from where it was.
"""

from __future__ import annotations

import dataclasses

from PySide6 import QtCore, QtWidgets

from groundstation.estimation import ESTIMATORS, about, label, unmet_needs
from groundstation.session.product import AIDING_TABLES
from groundstation.session.view import Session

SHOWN_COLUMNS = 4  # "show" check boxes per row
MESSAGE_LINES = 3  # "applied: ..." for a few estimators at once
COMPILING_TIP = "compiling for this machine (once, in the background); shown when ready"


def defaults(name: str) -> dict[str, float]:
    return dataclasses.asdict(ESTIMATORS[name].Settings())


class SettingBox(QtWidgets.QDoubleSpinBox):
    """A setting's field that the mouse wheel changes only once clicked into: scrolling the panel past it
    must not retune an estimator unseen (issue 34: AHF λ max went from 2.000 to 1.960 so)."""

    def __init__(self, **options):
        super().__init__(**options)
        self.setFocusPolicy(QtCore.Qt.StrongFocus)  # no focus from the wheel

    def wheelEvent(self, event) -> None:
        if self.hasFocus():
            super().wheelEvent(event)
        else:
            event.ignore()  # to the scrolling panel


class EstimatorPanel(QtWidgets.QGroupBox):
    visibilityChanged = QtCore.Signal(str, bool)  # legend label, shown
    otherShown = QtCore.Signal(str, bool)  # an added session's estimator, shown: plotted beside its others
    sessionChosen = QtCore.Signal(int)  # a row of the Sessions tab, chosen in the panel's box
    sendToAircraft = QtCore.Signal(dict)  # AHF setting -> value, for set_filter_param
    replayAsked = QtCore.Signal(tuple, dict)  # a replay's estimators, {estimator: {setting: value}} forced

    def __init__(self, parent=None):
        super().__init__(parent)  # titled by its tab
        self.session: Session | None = None
        self.label = ""  # the session's name: "" for the window's own, "S2" for one added beside it
        self.shown: dict[str, QtWidgets.QCheckBox] = {}
        self.boxes: dict[tuple[str, str], QtWidgets.QDoubleSpinBox] = {}
        self.message = QtWidgets.QLabel()
        self.message.setWordWrap(True)
        # Its room from the start: a message appearing after Apply must not move the fields (the next
        # click would land on another one).
        self.message.setFixedHeight(MESSAGE_LINES * self.message.fontMetrics().lineSpacing())
        self.message.setAlignment(QtCore.Qt.AlignTop | QtCore.Qt.AlignLeft)
        self.session_box = QtWidgets.QComboBox()  # which session it tunes, said first and chosen here
        self.session_box.setSizeAdjustPolicy(QtWidgets.QComboBox.AdjustToMinimumContentsLengthWithIcon)
        self.session_box.setMinimumContentsLength(12)  # a long source's name must not widen the side column
        self.session_box.activated.connect(self.sessionChosen)
        self.fields = QtWidgets.QWidget()  # all but the box: disabled with no session to tune
        outer = QtWidgets.QFormLayout(self)
        outer.addRow("session", self.session_box)
        outer.addRow(self.fields)
        self._layout = QtWidgets.QFormLayout(self.fields)
        self._layout.setContentsMargins(0, 0, 0, 0)
        self._buttons = QtWidgets.QHBoxLayout()
        # The buttons first: in sight as soon as the tab is (at 1280x800, below the fields they were under the fold).
        self._layout.addRow(self._buttons)
        self._layout.addRow(self.message)
        self._shown_row = QtWidgets.QGridLayout()
        self._layout.addRow("show", self._shown_row)
        # estimator -> (setting, symbol, unit), as the estimators offer them (``Estimator.tunable``)
        self.tunable = {name: about(name).tunable for name in ESTIMATORS if about(name).tunable}
        for name, settings in self.tunable.items():
            for setting, text, unit in settings:
                box = SettingBox(decimals=3, minimum=0.0, maximum=100.0, singleStep=0.01, suffix=f" {unit}")
                self.boxes[name, setting] = box
                self._layout.addRow(f"{label(name)} {text}", box)
        apply_button = QtWidgets.QPushButton("Apply")
        apply_button.clicked.connect(self.apply)
        defaults_button = QtWidgets.QPushButton("Defaults")
        defaults_button.clicked.connect(self.restore_defaults)
        self.send_button = QtWidgets.QPushButton("Send AHF λ to aircraft")
        self.send_button.clicked.connect(lambda: self.sendToAircraft.emit(self.values("ahf")))
        for button in (apply_button, defaults_button, self.send_button):
            self._buttons.addWidget(button)
        self.fields.setEnabled(False)

    def set_choices(self, names: list[str], current: int) -> None:
        """The sessions its box offers (the Sessions tab's rows) and the one it tunes."""
        self.session_box.blockSignals(True)
        if [self.session_box.itemText(i) for i in range(self.session_box.count())] != names:
            self.session_box.clear()
            self.session_box.addItems(names)
        self.session_box.setCurrentIndex(current)
        self.session_box.setToolTip(names[current] if 0 <= current < len(names) else "")
        self.session_box.blockSignals(False)

    def set_session(self, session: Session | None, visible_labels: set[str], session_name: str = "") -> None:
        """Fill the fields from the settings in effect; one "show" box per comparison estimator.
        ``session_name``: "" for the window's own, "S2" for one added beside it (``label``)."""
        self.session, self.label = session, session_name
        self.fields.setEnabled(session is not None)  # the box stays: another session can be chosen
        self.message.setText(f"{session_name} is being computed" if session is None and session_name else "")
        while self._shown_row.count():
            box = self._shown_row.takeAt(0).widget()
            box.hide()  # off the panel now: deleteLater waits for the outermost event loop, and a box
            box.setParent(self)  # made a window of its own (setParent(None)) took the keyboard from the window
            box.deleteLater()
        self.shown = {}
        if session is None:
            return
        # An autopilot has no AHF; the Uplink tab sends to the window's own session.
        self.send_button.setEnabled(not session_name and session.source.can_send and session.view.protocol == "gs")
        self.send_button.setToolTip(f"the Uplink tab sends to the window's own session, not {session_name}"
                                    if session_name else "")
        filters = session.view.filters
        offered = [*filters[1:], *(n for n in ESTIMATORS if n not in filters)] if self.replay else filters[1:]
        for index, name in enumerate(offered):
            box = QtWidgets.QCheckBox(label(name))
            box.setChecked(self.legend_label(name) in visible_labels and name in filters)
            box.toggled.connect(lambda on, name=name: self._shown_changed(name, on))
            self.shown[name] = box
            self._shown_row.addWidget(box, *divmod(index, SHOWN_COLUMNS))
        settings = session.view.settings()
        for name, fields in self.tunable.items():
            for setting, _, unit in fields:
                box = self.boxes[name, setting]
                box.setEnabled(name in settings)
                box.setSuffix(f" {unit}" if name in settings else "")
                if name in settings:
                    box.setValue(settings[name][setting])
                else:
                    box.clear()  # no number for an estimator the session does not run

    def legend_label(self, name: str) -> str:
        """Estimator ``name``'s curves' label for this session: "HF" for the window's own, "S2 HF"."""
        return f"{self.label} {label(name)}" if self.label else label(name)

    @property
    def replay(self) -> bool:
        return self.session is not None and self.session.source.is_replay

    def _shown_changed(self, name: str, on: bool) -> None:
        if self.label:  # an added session plots only the estimators asked for
            self.otherShown.emit(name, on)
        self.visibilityChanged.emit(self.legend_label(name), on)
        if on and (why := unmet_needs(name, self._aiding())):  # shown, and said to be little use so far
            self.message.setText(f"{why}; this session has none so far")
        filters = self.session.view.filters
        if on and name not in filters:  # only a replay offers it: compute it again with this estimator too
            self.replayAsked.emit((*filters, name), self._forced())

    def _aiding(self) -> set[str]:
        """The aiding the session has had so far (``product.AIDING_TABLES``: a sensor table with rows)."""
        tables = self.session.view.tables
        return {need for need, table in AIDING_TABLES.items() if table in tables and len(tables[table])}

    def _forced(self) -> dict[str, dict[str, float]]:
        """The fields of every estimator the session runs: the settings a recomputed replay is to use."""
        return {name: self.values(name) for name in self.tunable if name in self.session.view.filters}

    def sync_shown(self, visible_labels: set[str]) -> None:
        """Follow the legend, where curves can be switched too."""
        for name, box in self.shown.items():
            box.blockSignals(True)  # reflecting the legend, not a new request
            box.setChecked(self.legend_label(name) in visible_labels)
            box.blockSignals(False)

    def mark_uncompiled(self, names) -> None:
        """The estimators whose kernels are compiling (a first start) say so: "…" after the name (short: four
        boxes a row must fit the side column) and why in the tooltip; a file's cannot be asked for meanwhile
        (computed without them, the window adds them when compiled)."""
        for name, box in self.shown.items():
            waiting = name in names
            box.setText(f"{label(name)} …" if waiting else label(name))
            box.setToolTip(COMPILING_TIP if waiting else "")
            box.setEnabled(not (waiting and self.replay))

    def values(self, name: str) -> dict[str, float]:
        return {setting: self.boxes[name, setting].value() for setting, _, _ in self.tunable[name]}

    def apply(self) -> None:
        """Change every estimator whose fields differ from the settings in effect (a replay: compute it again)."""
        current = self.session.view.settings()
        if self.replay:
            if any(v != current[name][k] for name, values in self._forced().items() for k, v in values.items()):
                self.message.setText(f"recomputing {self.label or 'the session'} with these settings…")
                self.replayAsked.emit(self.session.view.filters, self._forced())
            else:
                self.message.setText("nothing changed")
            return
        changed = []
        for name in self.tunable:
            if name not in current:
                continue
            overrides = {k: v for k, v in self.values(name).items() if v != current[name][k]}
            if not overrides:
                continue
            try:
                self.session.change_settings(name, overrides)
            except ValueError as error:
                self.message.setText(f"{label(name)}: {error}")
                return
            symbols = {setting: text for setting, text, _ in self.tunable[name]}  # as the fields are labelled
            changed.append(f"{label(name)} " + ", ".join(f"{symbols[k]} = {v:g}" for k, v in overrides.items()))
        to = f" to {self.label}" if self.label else ""
        self.message.setText((f"applied{to}: " + "; ".join(changed)) if changed else "nothing changed")

    def restore_defaults(self) -> None:
        for (name, setting), box in self.boxes.items():
            box.setValue(defaults(name)[setting])
        self.apply()

"""The estimator panel: show or hide the comparison estimators, tune AHF's λ bounds, HF's and
HF+mag's β and ECF's and ECF+mag's Kp/Ki live, back to the defaults, or send AHF's λ bounds to the aircraft.

A change goes through ``LiveSession.change_settings``: it applies from the next sample, keeps the
attitude, and is written to the recording, so a replay changes it at the same point.
"""

from __future__ import annotations

import dataclasses

from PySide6 import QtCore, QtWidgets

from groundstation.estimation import ESTIMATORS
from groundstation.session.live import LiveSession
from groundstation.ui.live_view import LABELS

# estimator -> (setting, label, unit); units as in the settings dataclasses.
TUNABLE = {
    "ahf": (("lambda_min", "λ min", "rad/s"), ("lambda_max", "λ max", "rad/s")),
    "hf": (("beta", "β", "rad/s"),),
    "ecf": (("kp", "Kp", "rad/s"), ("ki", "Ki", "rad/s²")),
    "hfm": (("beta", "β", "rad/s"),),
    "ecfm": (("kp", "Kp", "rad/s"), ("ki", "Ki", "rad/s²")),
}
SHOWN_COLUMNS = 4  # "show" check boxes per row


def defaults(name: str) -> dict[str, float]:
    return dataclasses.asdict(ESTIMATORS[name].Settings())


class EstimatorPanel(QtWidgets.QGroupBox):
    visibilityChanged = QtCore.Signal(str, bool)  # legend label, shown
    sendToAircraft = QtCore.Signal(dict)  # AHF setting -> value, for set_filter_param

    def __init__(self, parent=None):
        super().__init__(parent)  # titled by its tab
        self.session: LiveSession | None = None
        self.shown: dict[str, QtWidgets.QCheckBox] = {}
        self.boxes: dict[tuple[str, str], QtWidgets.QDoubleSpinBox] = {}
        self.message = QtWidgets.QLabel()
        self.message.setWordWrap(True)
        self._layout = QtWidgets.QFormLayout(self)
        self._shown_row = QtWidgets.QGridLayout()
        self._layout.addRow("show", self._shown_row)
        for name, settings in TUNABLE.items():
            for setting, label, unit in settings:
                box = QtWidgets.QDoubleSpinBox(decimals=3, minimum=0.0, maximum=100.0, singleStep=0.01, suffix=f" {unit}")
                self.boxes[name, setting] = box
                self._layout.addRow(f"{LABELS[name]} {label}", box)
        apply_button = QtWidgets.QPushButton("Apply")
        apply_button.clicked.connect(self.apply)
        defaults_button = QtWidgets.QPushButton("Defaults")
        defaults_button.clicked.connect(self.restore_defaults)
        send_button = QtWidgets.QPushButton("Send AHF λ to aircraft")
        send_button.clicked.connect(lambda: self.sendToAircraft.emit(self.values("ahf")))
        buttons = QtWidgets.QHBoxLayout()
        for button in (apply_button, defaults_button, send_button):
            buttons.addWidget(button)
        self._layout.addRow(buttons)
        self._layout.addRow(self.message)
        self.setEnabled(False)

    def set_session(self, session: LiveSession | None, visible_labels: set[str]) -> None:
        """Fill the fields from the settings in effect; one "show" box per comparison estimator."""
        self.session = session
        self.setEnabled(session is not None)
        self.message.clear()
        while self._shown_row.count():
            self._shown_row.takeAt(0).widget().deleteLater()
        self.shown = {}
        if session is None:
            return
        for index, name in enumerate(session.pipeline.filters[1:]):
            box = QtWidgets.QCheckBox(LABELS.get(name, name))
            box.setChecked(LABELS.get(name, name) in visible_labels)
            box.toggled.connect(lambda on, label=box.text(): self.visibilityChanged.emit(label, on))
            self.shown[name] = box
            self._shown_row.addWidget(box, *divmod(index, SHOWN_COLUMNS))
        settings = session.pipeline.settings()
        for (name, setting), box in self.boxes.items():
            box.setEnabled(name in settings)
            if name in settings:
                box.setValue(settings[name][setting])

    def sync_shown(self, visible_labels: set[str]) -> None:
        """Follow the legend, where curves can be switched too."""
        for name, box in self.shown.items():
            box.blockSignals(True)  # reflecting the legend, not a new request
            box.setChecked(LABELS.get(name, name) in visible_labels)
            box.blockSignals(False)

    def values(self, name: str) -> dict[str, float]:
        return {setting: self.boxes[name, setting].value() for setting, _, _ in TUNABLE[name]}

    def apply(self) -> None:
        """Change every estimator whose fields differ from the settings in effect."""
        current = self.session.pipeline.settings()
        changed = []
        for name in TUNABLE:
            if name not in current:
                continue
            overrides = {k: v for k, v in self.values(name).items() if v != current[name][k]}
            if not overrides:
                continue
            try:
                self.session.change_settings(name, overrides)
            except ValueError as error:
                self.message.setText(f"{LABELS[name]}: {error}")
                return
            changed.append(f"{LABELS[name]} " + ", ".join(f"{k} = {v:g}" for k, v in overrides.items()))
        self.message.setText(("applied: " + "; ".join(changed)) if changed else "nothing changed")

    def restore_defaults(self) -> None:
        for (name, setting), box in self.boxes.items():
            box.setValue(defaults(name)[setting])
        self.apply()

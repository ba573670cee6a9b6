"""The Parameters tab: an autopilot's parameters (``view.parameters``: MAVLink PARAM_VALUE, DataFlash PARM,
ULog parameters) in a table, filtered as the user types (a part of the name, any case). Their changes
during the session are in the Events tab."""

from __future__ import annotations

from PySide6 import QtWidgets

from groundstation.session.view import Session


def shown_value(value: float) -> str:
    """Integers as integers (most parameters are), others to float32's precision, which they are sent in."""
    return f"{value:.0f}" if float(value).is_integer() else f"{value:.7g}"


class ParametersView(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self._shown: dict[str, float] = {}
        self.filter_box = QtWidgets.QLineEdit()
        self.filter_box.setPlaceholderText("Filter parameters (part of a name)")
        self.filter_box.setClearButtonEnabled(True)
        self.filter_box.textChanged.connect(self._filter)
        self.count_label = QtWidgets.QLabel("no parameters")
        self.table = QtWidgets.QTableWidget(0, 2)
        self.table.setHorizontalHeaderLabels(["parameter", "value"])
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.filter_box)
        layout.addWidget(self.count_label)
        layout.addWidget(self.table, 1)

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self._shown = {}
        self.table.setRowCount(0)
        self.refresh()

    def refresh(self) -> None:
        """The table again when the parameters changed (a live link's download, a change)."""
        if self.session is None:
            return
        with self.session.lock:
            parameters = dict(self.session.view.parameters)
        if parameters == self._shown:
            return
        self._shown = parameters
        self.table.setRowCount(len(parameters))
        for row, name in enumerate(sorted(parameters)):
            self.table.setItem(row, 0, QtWidgets.QTableWidgetItem(name))
            self.table.setItem(row, 1, QtWidgets.QTableWidgetItem(shown_value(parameters[name])))
        self.table.resizeColumnToContents(0)
        self._filter(self.filter_box.text())

    def visible_names(self) -> list[str]:
        return [self.table.item(row, 0).text() for row in range(self.table.rowCount()) if not self.table.isRowHidden(row)]

    def _filter(self, text: str) -> None:
        needle = text.strip().casefold()
        for row in range(self.table.rowCount()):
            self.table.setRowHidden(row, needle not in self.table.item(row, 0).text().casefold())
        total = self.table.rowCount()
        shown = len(self.visible_names())
        self.count_label.setText("no parameters" if not total else f"{shown} of {total} parameters")

"""The Parameters tab: an autopilot's parameters (``view.parameters``: MAVLink PARAM_VALUE, DataFlash PARM,
ULog parameters) in a table with what each means, as Mission Planner and Flight Review show them
(``autopilot.parameter_docs``: description, units, range, the meaning of the value, the default), the
non-default ones in bold and, at a click, alone; filtered as the user types (a part of the name or of the
description, any case). A label says where the descriptions come from, or how to get them. The side panel is
narrow for seven columns: "Open in a window" shows the same table in a window of its own, as wide as the
flyer makes it (Mission Planner's full parameter list), kept on the same session. Their changes during the
session are in the Events tab."""

from __future__ import annotations

import dataclasses
import html

from PySide6 import QtCore, QtWidgets

from groundstation.autopilot.parameter_docs import ParameterDoc, ParameterDocs, docs_for, non_default, shown_value
from groundstation.errors import UserError
from groundstation.session.view import Session

COLUMNS = ("parameter", "value", "default", "units", "range", "meaning", "description")
DESCRIPTION = COLUMNS.index("description")
COLUMN_MAX_PX = 220  # the description gets the rest of the width
NON_DEFAULT_TIP = "Only the parameters whose value is not their default (where the default is known)"
NO_DEFAULTS_TIP = ("No defaults known: a MAVLink link or .tlog does not carry them (a DataFlash log of ArduPilot 4.3 on "
                   "and a ULog of PX4 1.12 on do)")


class ParametersView(QtWidgets.QWidget):
    def __init__(self, parent=None, detachable: bool = True):
        super().__init__(parent)
        self.session: Session | None = None
        self.detached: ParametersView | None = None  # the window "Open in a window" opened, once opened
        self._shown: tuple[dict[str, float], dict[str, float]] = ({}, {})
        self._docs = ParameterDocs({}, "")
        self._non_default: set[str] = set()
        self.filter_box = QtWidgets.QLineEdit()
        self.filter_box.setPlaceholderText("Filter parameters (part of a name or of a description)")
        self.filter_box.setClearButtonEnabled(True)
        self.filter_box.textChanged.connect(self._filter)
        self.non_default_box = QtWidgets.QCheckBox("Non-default only")
        self.non_default_box.toggled.connect(lambda _: self._filter(self.filter_box.text()))
        self.count_label = QtWidgets.QLabel("no parameters")
        self.source_label = QtWidgets.QLabel()
        self.source_label.setWordWrap(True)
        self.table = QtWidgets.QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        self.table.setWordWrap(False)
        self.table.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 6)  # a list, not a form
        bar = QtWidgets.QHBoxLayout()
        bar.addWidget(self.filter_box, 1)
        bar.addWidget(self.non_default_box)
        if detachable:
            self.window_button = QtWidgets.QPushButton("Open in a window")
            self.window_button.clicked.connect(self.open_window)
            bar.addWidget(self.window_button)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(bar)
        layout.addWidget(self.count_label)
        layout.addWidget(self.source_label)
        layout.addWidget(self.table, 1)

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self._shown = ({}, {})
        self.table.setRowCount(0)
        self.source_label.clear()
        self.refresh()
        if self.detached is not None:
            self.detached.set_session(session)

    def open_window(self) -> None:
        if self.detached is None:
            self.detached = ParametersView(detachable=False)
            self.detached.setParent(self, QtCore.Qt.Window)  # a window of its own, closed with the main one
            self.detached.setWindowTitle("Parameters")
            self.detached.resize(1100, 700)
            self.detached.set_session(self.session)
        self.detached.show()
        self.detached.raise_()
        self.detached.activateWindow()

    def refresh(self) -> None:
        """The table again when the parameters changed (a live link's download, a change)."""
        if self.detached is not None and self.detached.isVisible():
            self.detached.refresh()
        if self.session is None:
            return
        with self.session.lock:
            shown = (dict(self.session.view.parameters), dict(self.session.view.parameter_defaults))
        if shown == self._shown:
            return
        parameters, defaults = shown
        if (set(parameters), defaults) != (set(self._shown[0]), self._shown[1]):  # a new name or default: the docs again
            self._docs = self._docs_of(parameters, defaults)
            self.source_label.setText(f"Descriptions: {self._docs.source}" if self._docs.described else self._docs.source)
            known = any(doc.default is not None for doc in self._docs.docs.values())
            self.non_default_box.setEnabled(known)
            self.non_default_box.setToolTip(NON_DEFAULT_TIP if known else NO_DEFAULTS_TIP)
        self._shown = shown
        self.table.setRowCount(len(parameters))
        self._non_default = set()
        for row, name in enumerate(sorted(parameters)):
            value, doc = parameters[name], self._docs.get(name)
            cells = (name, shown_value(value), shown_value(doc.default) if doc.default is not None else "", doc.units,
                     doc.range_text(), doc.meaning(value), doc.description)
            changed = non_default(value, doc)
            tip = _tooltip(doc)
            for column, text in enumerate(cells):
                item = QtWidgets.QTableWidgetItem(text)
                item.setToolTip(tip)
                if changed and column == 1:
                    font = item.font()
                    font.setBold(True)
                    item.setFont(font)
                self.table.setItem(row, column, item)
            if changed:
                self._non_default.add(name)
        for column in range(DESCRIPTION):  # each as wide as its text, a long meaning (a bitmask's bits) cut: its tooltip has it
            self.table.resizeColumnToContents(column)
            self.table.setColumnWidth(column, min(self.table.columnWidth(column), COLUMN_MAX_PX))
        self._filter(self.filter_box.text())

    def _docs_of(self, parameters: dict[str, float], defaults: dict[str, float]) -> ParameterDocs:
        played = self.session.file() if self.session is not None else None
        try:
            return docs_for(parameters, played[0].parent if played else None, defaults)
        except UserError as error:  # a parameters.json beside the log that is not one: said, and the rest still shown
            fallback = docs_for(parameters, None, defaults)
            return dataclasses.replace(fallback, source=f"{error}. {fallback.source}")

    def visible_names(self) -> list[str]:
        return [self.table.item(row, 0).text() for row in range(self.table.rowCount()) if not self.table.isRowHidden(row)]

    def _filter(self, text: str) -> None:
        needle = text.strip().casefold()
        only_changed = self.non_default_box.isChecked() and self.non_default_box.isEnabled()
        for row in range(self.table.rowCount()):
            name = self.table.item(row, 0).text()
            found = needle in name.casefold() or needle in self.table.item(row, DESCRIPTION).text().casefold()
            self.table.setRowHidden(row, not found or (only_changed and name not in self._non_default))
        total = self.table.rowCount()
        shown = len(self.visible_names())
        self.count_label.setText("no parameters" if not total else f"{shown} of {total} parameters")


def _tooltip(doc: ParameterDoc) -> str:
    """The whole of what is known of it, for a description the column cuts short and an enum's every value."""
    lines = [f"<b>{html.escape(doc.name)}</b>" + (f": {html.escape(doc.title)}" if doc.title else "")]
    if doc.description:
        lines.append(html.escape(doc.description))
    facts = [f"units {doc.units}" if doc.units else "", f"range {doc.range_text()}" if doc.range_text() else "",
             f"default {shown_value(doc.default)}" if doc.default is not None else ""]
    if any(facts):
        lines.append(html.escape(", ".join(f for f in facts if f)))
    labels = [f"{shown_value(v)}: {label}" for v, label in sorted(doc.values.items())] or [f"bit {b}: {label}" for b, label in sorted(doc.bits.items())]
    if labels:
        lines.append(html.escape("; ".join(labels)))
    return "<p style='white-space:normal'>" + "<br>".join(lines) + "</p>" if doc.description or doc.title else ""

"""The event console: the session's events (``view.events``: configuration, warnings, commands
and their ACKs, settings changes, reboots and clock jumps, gaps, the port lost and back, the
recording started, stopped or failed; an autopilot's texts, modes and parameter changes) with their
session times; a click moves the view there. Alarms and an autopilot's errors are red.
"""

from __future__ import annotations

import math

from PySide6 import QtCore, QtGui, QtWidgets

from firmware_protocol import SPEC
from groundstation.autopilot.messages import ALARM_SEVERITIES
from groundstation.session.view import Session, event_session_time_s

# Kinds a pilot must not miss, shown in red.
ALARMS = frozenset({"warning", "config_conflict", "disconnected", "device_reset", "clock_jump", "gap", "recording_failed"})
MIN_ROWS = 12  # the table's height at least, in one-line rows
HIDDEN_FIELDS = frozenset({"kind", "t_host_ns", "wall_time", "session_time_s"})
# Events that carry a frame's values (CONFIG, ACK) show its enum fields by member name ("unknown" included).
ENUM_FIELDS = {kind: {f.name: f for f in SPEC.frame(kind.upper()).fields if f.enum} for kind in ("config", "ack")}


def describe(event: dict) -> str:
    """``mode RTL, armed``: each field by its name and value; a flag by its name ("not armed" when false),
    a field without a value left out (not "severity None")."""
    enums = ENUM_FIELDS.get(event.get("kind"), {})
    return ", ".join(f"{k} {SPEC.enum_name(enums[k], v)}" if k in enums else (k if v else f"not {k}") if isinstance(v, bool)
                     else f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}"
                     for k, v in event.items() if k not in HIDDEN_FIELDS and v is not None)


class EventConsole(QtWidgets.QWidget):
    timeRequested = QtCore.Signal(float)  # seconds into the session

    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.shown = 0  # events listed
        self.table = QtWidgets.QTableWidget(0, 3)
        self.table.setHorizontalHeaderLabels(["time (s)", "event", "details"])
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.verticalHeader().hide()
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectRows)
        # The details wrap in their column, rows as tall as they need: the side column is narrow, and a
        # detail cut at its edge ("CONFIG: firmware 1.2.0, ±…") says nothing.
        self.table.setWordWrap(True)
        self.table.setTextElideMode(QtCore.Qt.ElideNone)
        self.table.setMinimumHeight(MIN_ROWS * self.table.verticalHeader().defaultSectionSize())
        self._wrapped_at = -1  # the details column's width the rows were last wrapped to
        self.table.cellClicked.connect(self._clicked)
        self.table.setToolTip("Click an event to show its moment in the plots")
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.table)

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self.shown = 0
        self.table.setRowCount(0)

    def refresh(self) -> None:
        if self.table.columnWidth(2) != self._wrapped_at:  # the details column (stretched) changed width:
            self._wrapped_at = self.table.columnWidth(2)  # the tab shown, the window resized
            self.table.resizeRowsToContents()
        if self.session is None:
            return
        view = self.session.view
        with self.session.lock:
            new = view.events[self.shown :]
        if not new:
            return
        at_bottom = self.table.verticalScrollBar().value() == self.table.verticalScrollBar().maximum()
        for event in new:
            row = self.table.rowCount()
            self.table.insertRow(row)
            t_s = event_session_time_s(view, event)
            cells = (QtWidgets.QTableWidgetItem(f"{t_s:9.2f}"), QtWidgets.QTableWidgetItem(event.get("kind", "?")),
                     QtWidgets.QTableWidgetItem(describe(event)))
            cells[0].setData(QtCore.Qt.UserRole, t_s)
            cells[2].setToolTip(describe(event))
            for column, cell in enumerate(cells):
                if event.get("kind") in ALARMS or event.get("severity") in ALARM_SEVERITIES:
                    cell.setForeground(QtGui.QColor("#b00020"))
                self.table.setItem(row, column, cell)
        first = self.shown
        self.shown += len(new)
        self.table.resizeColumnToContents(0)
        self.table.resizeColumnToContents(1)
        for row in range(first, self.shown):
            self.table.resizeRowToContents(row)
        if at_bottom:
            self.table.scrollToBottom()

    def times(self) -> list[float]:
        return [self.table.item(row, 0).data(QtCore.Qt.UserRole) for row in range(self.table.rowCount())]

    def _clicked(self, row: int, _column: int) -> None:
        t_s = self.table.item(row, 0).data(QtCore.Qt.UserRole)
        if math.isfinite(t_s):
            self.timeRequested.emit(t_s)

"""The connection bar: the source box (any string ``open_source`` accepts, with the serial ports
found, refreshed as devices come and go, and the recent sources), baud, Connect/Disconnect, the
simulated bridge, "Open file…" (a recording or a flight log) and "Export…". It only asks; the window acts.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from groundstation.export.request import FORMATS as EXPORT_FORMATS, either
from groundstation.sources import list_ports
from groundstation.sources.spec import accepted_forms, source_forms

BAUD_RATES = (9600, 57600, 115200, 230400, 460800, 921600, 1000000, 2000000)
AUTO_BAUD = "auto"  # the source's own default: 115200 for the project's bridge, 57600 for a MAVLink radio
PORT_REFRESH_MS = 1000


class ConnectionBar(QtWidgets.QWidget):
    connectRequested = QtCore.Signal(str, int)  # source string, baud (0: the source's default)
    disconnectRequested = QtCore.Signal()
    demoRequested = QtCore.Signal()
    recordingRequested = QtCore.Signal()
    exportRequested = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.port_box = QtWidgets.QComboBox()
        self.port_box.setEditable(True)  # a pty, socket://, udp://, sim:, a recording: anything open_source takes
        self.port_box.setInsertPolicy(QtWidgets.QComboBox.NoInsert)
        self.port_box.setCompleter(None)  # the list's lines carry descriptions; completing with them garbles the text
        self.port_box.lineEdit().setPlaceholderText(source_forms(commonest=True))
        self.port_box.setToolTip("The source, one of:" + accepted_forms())
        self.port_box.setMinimumContentsLength(28)
        self.port_box.setSizeAdjustPolicy(QtWidgets.QComboBox.AdjustToMinimumContentsLengthWithIcon)
        self.port_box.activated.connect(self._take_listed)
        self.port_box.editTextChanged.connect(self._enable_connect)
        self.port_box.lineEdit().returnPressed.connect(self._connect)
        self.baud_box = QtWidgets.QComboBox()
        self.baud_box.setEditable(True)  # any rate the adapter supports
        self.baud_box.addItems([AUTO_BAUD, *map(str, BAUD_RATES)])
        self.baud_box.setToolTip("auto: 115200 for the project's bridge, 57600 for a MAVLink radio (mavlink:PORT); "
                                 "a ?baud= in the source string wins")
        self.connect_button = QtWidgets.QPushButton("Connect")
        self.disconnect_button = QtWidgets.QPushButton("Disconnect")
        self.demo_button = QtWidgets.QPushButton("Simulated bridge (demo)")
        self.open_button = QtWidgets.QPushButton("Open file…")
        self.export_button = QtWidgets.QPushButton("Export…")
        self.export_button.setToolTip("The current or last session's recording to "
                                      + either(f.name for f in EXPORT_FORMATS.values()))
        self.export_button.clicked.connect(self.exportRequested)
        self.connect_button.clicked.connect(self._connect)
        self.disconnect_button.clicked.connect(self.disconnectRequested)
        self.demo_button.clicked.connect(self.demoRequested)
        self.open_button.clicked.connect(self.recordingRequested)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        for widget in (QtWidgets.QLabel("Source"), self.port_box, QtWidgets.QLabel("Baud"), self.baud_box,
                       self.connect_button, self.disconnect_button):
            layout.addWidget(widget)
        layout.addSpacing(16)
        layout.addWidget(self.demo_button)
        layout.addWidget(self.open_button)
        layout.addWidget(self.export_button)
        layout.addStretch(1)
        self._ports: list[dict[str, str]] = []
        self._recent: list[str] = []
        self._unfilled = False
        self.set_connected(False)
        self.refresh_ports()
        self._timer = QtCore.QTimer(self, interval=PORT_REFRESH_MS, timeout=self.refresh_ports)
        self._timer.start()

    @property
    def source(self) -> str:
        """What the user typed or picked: the string handed to ``open_source``."""
        return self.port_box.currentText().strip()

    def listed(self) -> list[str]:
        """The source strings in the box's list: the ports found, then the recent sources."""
        return [self.port_box.itemData(i) for i in range(self.port_box.count()) if self.port_box.itemData(i)]

    def refresh_ports(self) -> None:
        """Re-list the ports when they changed; what the user typed or picked stays as it is."""
        ports = list_ports()
        if ports != self._ports or self._unfilled:
            self._ports = ports
            self._fill()

    def set_recent(self, recent: list[str]) -> None:
        """The sources connected to lately, newest first, listed below the ports."""
        if list(recent) != self._recent:
            self._recent = list(recent)
            self._fill()

    def _fill(self) -> None:
        if self.port_box.view().isVisible():
            self._unfilled = True  # the user is choosing from the open list: rebuild it on the next refresh
            return
        self._unfilled = False
        edit = self.port_box.lineEdit()
        text, cursor = edit.text(), edit.cursorPosition()
        self.port_box.blockSignals(True)
        self.port_box.clear()
        for port in self._ports:
            details = ", ".join(x for x in (port["description"], port["vid_pid"]) if x and x != "n/a")
            self.port_box.addItem(f"{port['device']} — {details}" if details else port["device"], port["device"])
        recent = [r for r in self._recent if r not in (p["device"] for p in self._ports)]
        if self._ports and recent:
            self.port_box.insertSeparator(self.port_box.count())
        for spec in recent:
            self.port_box.addItem(spec, spec)
            self.port_box.setItemData(self.port_box.count() - 1, "used recently", QtCore.Qt.ToolTipRole)
        self.port_box.setCurrentIndex(-1)
        edit.setText(text)
        edit.setCursorPosition(cursor)
        self.port_box.blockSignals(False)

    def _take_listed(self, index: int) -> None:
        """A line of the list picked: the box holds its source string, not its description."""
        spec = self.port_box.itemData(index)
        if spec:
            self.port_box.setEditText(spec)

    def select(self, source: str | None, baud: int | None) -> None:
        """Preselect a remembered source and baud rate."""
        if source:
            self.port_box.setEditText(source)
        if baud:
            self.baud_box.setCurrentText(str(baud))

    @property
    def baud(self) -> int:
        """The chosen rate; 0 for "auto" (anything not a whole number is auto too)."""
        try:
            return max(int(self.baud_box.currentText()), 0)
        except ValueError:
            return 0

    def set_connected(self, connected: bool, file=None) -> None:
        """``file``: the file being played back: the box names it (not the port used before) and the
        button that stops it says "Close file"."""
        if file is not None:
            self.port_box.setEditText(str(file))
        self.disconnect_button.setText("Close file" if connected and file is not None else "Disconnect")
        self.disconnect_button.setEnabled(connected)
        self._enable_connect()

    def _enable_connect(self) -> None:
        # Also while a session runs: Connect (or Return) switches to the source typed (issue 24, defect 1).
        self.connect_button.setEnabled(bool(self.source))

    def _connect(self) -> None:
        if self.connect_button.isEnabled():
            self.connectRequested.emit(self.source, self.baud)

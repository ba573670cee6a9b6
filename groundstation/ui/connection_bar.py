"""The connection bar: serial port (refreshed as devices come and go), baud, Connect/Disconnect,
the simulated bridge, "Open recording…" and "Export…". It only asks; the window acts.
"""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from groundstation.sources import list_ports

BAUD_RATES = (9600, 57600, 115200, 230400, 460800, 921600, 1000000, 2000000)
DEFAULT_BAUD = 115200
PORT_REFRESH_MS = 1000


class ConnectionBar(QtWidgets.QWidget):
    connectRequested = QtCore.Signal(str, int)  # port, baud
    disconnectRequested = QtCore.Signal()
    demoRequested = QtCore.Signal()
    recordingRequested = QtCore.Signal()
    exportRequested = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.port_box = QtWidgets.QComboBox()
        self.port_box.setMinimumContentsLength(28)
        self.port_box.setSizeAdjustPolicy(QtWidgets.QComboBox.AdjustToMinimumContentsLengthWithIcon)
        self.baud_box = QtWidgets.QComboBox()
        self.baud_box.setEditable(True)  # any rate the adapter supports
        self.baud_box.addItems([str(b) for b in BAUD_RATES])
        self.baud_box.setCurrentText(str(DEFAULT_BAUD))
        self.connect_button = QtWidgets.QPushButton("Connect")
        self.disconnect_button = QtWidgets.QPushButton("Disconnect")
        self.demo_button = QtWidgets.QPushButton("Simulated bridge (demo)")
        self.open_button = QtWidgets.QPushButton("Open recording…")
        self.export_button = QtWidgets.QPushButton("Export…")
        self.export_button.setToolTip("The current or last session's recording to Excel, CSV or Parquet")
        self.export_button.clicked.connect(self.exportRequested)
        self.connect_button.clicked.connect(self._connect)
        self.disconnect_button.clicked.connect(self.disconnectRequested)
        self.demo_button.clicked.connect(self.demoRequested)
        self.open_button.clicked.connect(self.recordingRequested)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        for widget in (QtWidgets.QLabel("Port"), self.port_box, QtWidgets.QLabel("Baud"), self.baud_box,
                       self.connect_button, self.disconnect_button):
            layout.addWidget(widget)
        layout.addSpacing(16)
        layout.addWidget(self.demo_button)
        layout.addWidget(self.open_button)
        layout.addWidget(self.export_button)
        layout.addStretch(1)
        self.set_connected(False)
        self.refresh_ports()
        self._timer = QtCore.QTimer(self, interval=PORT_REFRESH_MS, timeout=self.refresh_ports)
        self._timer.start()

    def refresh_ports(self) -> None:
        """Re-list the ports, keeping the selection when that port is still there."""
        ports = list_ports()
        listed = [self.port_box.itemData(i) for i in range(self.port_box.count())]
        if [p["device"] for p in ports] == listed:
            return
        selected = self.port_box.currentData()
        self.port_box.clear()
        for port in ports:
            details = ", ".join(x for x in (port["description"], port["vid_pid"]) if x and x != "n/a")
            self.port_box.addItem(f"{port['device']} — {details}" if details else port["device"], port["device"])
        if not ports:
            self.port_box.setPlaceholderText("no serial ports found")
        index = self.port_box.findData(selected)
        if index >= 0:
            self.port_box.setCurrentIndex(index)
        self.connect_button.setEnabled(bool(ports) and not self.disconnect_button.isEnabled())

    def select(self, port: str | None, baud: int | None) -> None:
        """Preselect a remembered port and baud rate."""
        index = self.port_box.findData(port)
        if index >= 0:
            self.port_box.setCurrentIndex(index)
        if baud:
            self.baud_box.setCurrentText(str(baud))

    @property
    def baud(self) -> int:
        try:
            return int(self.baud_box.currentText())
        except ValueError:
            return DEFAULT_BAUD

    def set_connected(self, connected: bool) -> None:
        self.disconnect_button.setEnabled(connected)
        self.connect_button.setEnabled(not connected and self.port_box.count() > 0)

    def _connect(self) -> None:
        port = self.port_box.currentData()
        if port:
            self.connectRequested.emit(port, self.baud)

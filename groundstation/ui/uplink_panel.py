"""The uplink: firmware mode (raw, estimated, both), AHF parameters, CONFIG request, gyro bias
calibration at rest; each command's ACK (result and round trip) or its timeout, and the
firmware's configuration as its last CONFIG frame gave it. An autopilot on MAVLink gets only what
makes sense for it: a request for its IMU and attitude streams at a chosen rate (nothing that arms
or moves it).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from PySide6 import QtWidgets

from firmware_protocol import SPEC
from groundstation.autopilot.streams import MAX_REQUEST_RATE_HZ, REQUESTED_RATE_HZ
from groundstation.session.view import Session

ACK_TIMEOUT_S = 1.0
HISTORY = 4  # commands listed
MODES = SPEC.enums["mode"].values  # name -> value
FILTER_PARAMS = SPEC.enums["filter_param"].values
RESULTS = {value: name for name, value in SPEC.enums["ack_result"].values.items()}
GYRO_CALIBRATION = SPEC.frame("CONFIG").field("gyro_calibration")  # "unknown" from firmware older than the field
MODE_NAMES = {value: name for name, value in MODES.items()}


@dataclass
class Sent:
    seq: int
    text: str
    sent_ns: int
    answer: str = ""  # empty while waiting


class UplinkPanel(QtWidgets.QGroupBox):
    def __init__(self, parent=None):
        super().__init__(parent)  # titled by its tab
        self.session: Session | None = None
        self.sent: list[Sent] = []
        self._events_seen = 0
        self._config_mode: int | None = None  # the mode of the last CONFIG, which the mode box was set to
        self.mode_box = QtWidgets.QComboBox()
        self.mode_box.addItems(list(MODES))
        self.mode_button = QtWidgets.QPushButton("Set mode")
        self.mode_button.clicked.connect(
            lambda: self.send("set_mode", MODES[self.mode_box.currentText()], text=f"set_mode {self.mode_box.currentText()}"))
        self.config_button = QtWidgets.QPushButton("Request CONFIG")
        self.config_button.clicked.connect(lambda: self.send("request_config"))
        self.calibration_s = QtWidgets.QDoubleSpinBox(decimals=1, minimum=0.5, maximum=60.0, value=2.0, suffix=" s")
        self.calibrate_button = QtWidgets.QPushButton("Calibrate gyro")
        self.calibrate_button.setToolTip("Keep the aircraft still: the firmware averages the gyro to find its bias")
        self.calibrate_button.clicked.connect(lambda: self.send("calibrate_gyro", 0, self.calibration_s.value()))
        self.config_label = QtWidgets.QLabel("no CONFIG yet")
        self.config_label.setWordWrap(True)
        self.answers = QtWidgets.QLabel()
        self.answers.setWordWrap(True)
        self.gs_controls = QtWidgets.QWidget()  # the project's firmware
        rows = QtWidgets.QFormLayout(self.gs_controls)
        rows.setContentsMargins(0, 0, 0, 0)
        rows.addRow(self._row(self.mode_box, self.mode_button, self.config_button))
        rows.addRow(self._row(QtWidgets.QLabel("at rest for"), self.calibration_s, self.calibrate_button))
        rows.addRow("firmware", self.config_label)
        rows.addRow("answers", self.answers)
        self.stream_rate_hz = QtWidgets.QDoubleSpinBox(decimals=0, minimum=1.0, maximum=MAX_REQUEST_RATE_HZ,
                                                       value=REQUESTED_RATE_HZ, suffix=" Hz")
        self.streams_button = QtWidgets.QPushButton("Request streams")
        self.streams_button.setToolTip("Ask the autopilot for its IMU and attitude at this rate "
                                       "(REQUEST_DATA_STREAM and SET_MESSAGE_INTERVAL)")
        self.streams_button.clicked.connect(self.request_streams)
        self.mavlink_controls = QtWidgets.QWidget()  # an autopilot
        rows = QtWidgets.QFormLayout(self.mavlink_controls)
        rows.setContentsMargins(0, 0, 0, 0)
        rows.addRow(self._row(QtWidgets.QLabel("IMU and attitude at"), self.stream_rate_hz, self.streams_button))
        note = QtWidgets.QLabel("An autopilot gets only stream-rate requests: nothing that arms or moves it.")
        note.setWordWrap(True)  # unwrapped, it widened the right column past its room (clipped on flight logs)
        rows.addRow(note)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.gs_controls)
        layout.addWidget(self.mavlink_controls)
        layout.addStretch()
        self.mavlink_controls.hide()
        self.setEnabled(False)

    @staticmethod
    def _row(*widgets) -> QtWidgets.QHBoxLayout:
        row = QtWidgets.QHBoxLayout()
        for widget in widgets:
            row.addWidget(widget)
        return row

    def set_session(self, session: Session | None) -> None:
        """Enabled only when the source can send (a replay has no aircraft to command)."""
        can_send = session is not None and session.source.can_send
        self.session = session if can_send else None
        self.setEnabled(can_send)
        mavlink = session is not None and session.view.protocol == "mavlink"
        self.gs_controls.setVisible(not mavlink)
        self.mavlink_controls.setVisible(mavlink)
        self.sent = []
        self._events_seen = 0
        self._config_mode = None
        self.answers.setText("")
        self.config_label.setText("no CONFIG yet" if can_send else "(this source cannot send: no uplink)")

    def send(self, command: str, param: int = 0, value: float = 0.0, text: str | None = None) -> None:
        if self.session is None:  # the source cannot send: its controls are disabled
            return
        seq = self.session.send_command(command, param, value)
        self.sent = [*self.sent, Sent(seq, text or command, time.monotonic_ns())][-HISTORY:]
        self._show_answers()

    def request_streams(self) -> None:
        if self.session is not None:
            self.session.request_streams(self.stream_rate_hz.value())

    def send_ahf(self, values: dict[str, float]) -> None:
        """AHF settings to the onboard filter, one set_filter_param each."""
        for setting, value in values.items():
            self.send("set_filter_param", FILTER_PARAMS[setting], value, f"{setting} = {value:g}")

    def refresh(self) -> None:
        if self.session is None:
            return
        events = self.session.view.events
        new, self._events_seen = events[self._events_seen :], len(events)
        for event in new:
            if event["kind"] == "ack":
                for sent in self.sent:
                    if sent.seq == event["command_seq"] and not sent.answer:
                        ms = (event["t_host_ns"] - sent.sent_ns) / 1e6
                        sent.answer = f"ACK {RESULTS.get(event['result'], event['result'])} ({ms:.0f} ms)"
        config = self.session.view.config
        if config is not None and config.get("mode") != self._config_mode:
            # The firmware's mode changed (or is first known): the box shows it until the user picks another.
            self._config_mode = config.get("mode")
            self.mode_box.setCurrentText(MODE_NAMES.get(self._config_mode, self.mode_box.currentText()))
        if config is not None:
            self.config_label.setText(
                f"mode {MODE_NAMES.get(config.get('mode'), '?')}, {config.get('rate_hz')} Hz, ±{config.get('accel_fs_g')} g, "
                f"±{config.get('gyro_fs_dps')} °/s, mounting {config.get('mounting')}, "
                f"gyro calibration {SPEC.enum_name(GYRO_CALIBRATION, config.get('gyro_calibration'))}")
        self._show_answers()

    def _show_answers(self) -> None:
        now = time.monotonic_ns()
        for sent in self.sent:
            if not sent.answer and now - sent.sent_ns > ACK_TIMEOUT_S * 1e9:
                sent.answer = f"no ACK within {ACK_TIMEOUT_S:g} s"
        self.answers.setText("\n".join(f"#{s.seq} {s.text}: {s.answer or 'waiting…'}" for s in reversed(self.sent)))

"""The vehicle badge in the status bar: an autopilot's flight mode and whether it is armed, always in
sight on a MAVLink link, as QGroundControl and Mission Planner show them (red when armed).

It shows the newest of the session's mode spans (``autopilot.modes.mode_spans``, which the plots' mode
bands draw too): live from the vehicle's HEARTBEAT, in a flight log from its own mode records. Hidden
for the project's own link and for files without an autopilot's modes.
"""

from __future__ import annotations

from PySide6 import QtWidgets

from groundstation.autopilot.modes import ModeSpan

STYLES = {
    True: "background:#c62828; color:white; padding:2px 8px; font-weight:bold",
    False: "background:#e0e0e0; color:#222; padding:2px 8px; font-weight:bold",
}


class VehicleBadge(QtWidgets.QLabel):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.setToolTip("The autopilot's flight mode and arming")
        self._shown: tuple | None = None
        self.hide()

    def refresh(self, spans: list[ModeSpan]) -> None:
        """Shows the newest of the session's mode spans (``autopilot.modes.mode_spans``); hidden without any."""
        shown = (spans[-1].mode, spans[-1].armed) if spans else None
        if shown == self._shown:
            return
        self._shown = shown
        self.setVisible(shown is not None)
        if shown is not None:
            mode, armed = shown
            self.setText(mode if armed is None else f"{'ARMED' if armed else 'disarmed'} · {mode}")
            self.setStyleSheet(STYLES[bool(armed)])

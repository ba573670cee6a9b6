"""The vehicle badge in the status bar: an autopilot's flight mode and whether it is armed, always in
sight on a MAVLink link, as QGroundControl and Mission Planner show them (red when armed).

It reads the session's ``vehicle_status`` events (the MAVLink front-end adds one when the vehicle's
HEARTBEAT changes mode or arming); the mode is the name the front-end gives it. Hidden for the
project's own link and for files without an autopilot's heartbeat.
"""

from __future__ import annotations

from PySide6 import QtWidgets

from groundstation.session.view import Session

STYLES = {
    True: "background:#c62828; color:white; padding:2px 8px; font-weight:bold",
    False: "background:#e0e0e0; color:#222; padding:2px 8px; font-weight:bold",
}


def vehicle_status(session: Session | None) -> dict | None:
    """The newest ``vehicle_status`` event of the session (None: no autopilot heartbeat yet)."""
    if session is None or session.view.protocol != "mavlink":
        return None
    with session.lock:
        return next((e for e in reversed(session.view.events) if e.get("kind") == "vehicle_status"), None)


class VehicleBadge(QtWidgets.QLabel):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.setToolTip("The autopilot's flight mode and arming, from its HEARTBEAT")
        self._shown: tuple | None = None
        self.hide()

    def refresh(self, session: Session | None) -> None:
        status = vehicle_status(session)
        shown = None if status is None else (str(status["mode"]), bool(status["armed"]))
        if shown == self._shown:
            return
        self._shown = shown
        self.setVisible(shown is not None)
        if shown is not None:
            mode, armed = shown
            self.setText(f"{'ARMED' if armed else 'disarmed'} · {mode}")
            self.setStyleSheet(STYLES[armed])

"""An artificial horizon with numeric pitch, roll and yaw (degrees, docs/conventions.md), and the
heading of the compass or the GPS when the session has one (0..360°, the source named). For
``RECONVERGE_S`` after the device rebooted (or its clock jumped) an amber line above them says the
estimates are re-converging: the estimators started over then (``EstimatorBank.restart``).

The horizon turns by -roll (right wing down tilts the horizon the other way, as seen from the
cockpit) and moves down by pitch (nose up shows more sky), ``VISIBLE_PITCH_DEG`` from the centre to
the edge, with a pitch ladder every 10°.
"""

from __future__ import annotations

import math

from PySide6 import QtCore, QtGui, QtWidgets

from groundstation import quaternion
from groundstation.session_parts.clock import DISCONTINUITIES
from groundstation.session_parts.estimators import RECONVERGE_S
from groundstation.session.view import Session
from groundstation.ui.attitude_3d import AttitudeView3D
from groundstation.ui.navigation import heading_now
from groundstation.ui.sample_streams import headline

SKY, GROUND, LINE = QtGui.QColor("#3a7bd5"), QtGui.QColor("#8b5a2b"), QtGui.QColor("white")
VISIBLE_PITCH_DEG = 30.0  # from the centre to the top edge
RESTART_WORDS = {"device_reset": "device reboot", "clock_jump": "device clock jump"}


def reconverging(events: list[dict], now_s: float) -> tuple[str, float] | None:
    """The newest restart (``device_reset``, ``clock_jump``) if it was less than ``RECONVERGE_S`` before
    session time ``now_s``: (its kind, the seconds left), else None."""
    for event in reversed(events):
        if event["kind"] in DISCONTINUITIES:
            left_s = event["session_time_s"] + RECONVERGE_S - now_s
            return (event["kind"], left_s) if left_s > 0 else None
    return None


class AttitudeIndicator(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.pitch_deg = self.roll_deg = self.yaw_deg = math.nan
        self.setMinimumSize(150, 150)
        self.setSizePolicy(QtWidgets.QSizePolicy.Expanding, QtWidgets.QSizePolicy.Fixed)

    def sizeHint(self) -> QtCore.QSize:
        return QtCore.QSize(240, 240)

    def set_attitude(self, yaw_deg: float, pitch_deg: float, roll_deg: float) -> None:
        if (yaw_deg, pitch_deg, roll_deg) != (self.yaw_deg, self.pitch_deg, self.roll_deg):
            self.yaw_deg, self.pitch_deg, self.roll_deg = yaw_deg, pitch_deg, roll_deg
            self.update()

    def paintEvent(self, event) -> None:
        side = min(self.width(), self.height())
        painter = QtGui.QPainter(self)
        painter.setRenderHint(QtGui.QPainter.Antialiasing)
        painter.translate(self.width() / 2, self.height() / 2)
        clip = QtGui.QPainterPath()
        clip.addEllipse(QtCore.QPointF(0, 0), side / 2 - 2, side / 2 - 2)
        painter.setClipPath(clip)
        known = not math.isnan(self.pitch_deg)
        px_per_deg = side / 2 / VISIBLE_PITCH_DEG
        painter.save()
        if known:
            painter.rotate(-self.roll_deg)
            painter.translate(0, self.pitch_deg * px_per_deg)
        big = side * 3
        painter.fillRect(QtCore.QRectF(-big, -big, 2 * big, big), SKY if known else QtGui.QColor("#999"))
        painter.fillRect(QtCore.QRectF(-big, 0, 2 * big, big), GROUND if known else QtGui.QColor("#777"))
        painter.setPen(QtGui.QPen(LINE, 2))
        painter.drawLine(QtCore.QPointF(-big, 0), QtCore.QPointF(big, 0))
        painter.setPen(QtGui.QPen(LINE, 1))
        for deg in range(-80, 90, 10):
            if deg:
                y, half = -deg * px_per_deg, side * (0.12 if deg % 20 == 0 else 0.06)
                painter.drawLine(QtCore.QPointF(-half, y), QtCore.QPointF(half, y))
                if deg % 20 == 0:
                    painter.drawText(QtCore.QPointF(half + 4, y + 4), f"{abs(deg)}")
        painter.restore()
        painter.setPen(QtGui.QPen(QtGui.QColor("#ffd400"), 3))  # the fixed aircraft symbol
        wing = side * 0.22
        painter.drawLine(QtCore.QPointF(-wing, 0), QtCore.QPointF(-wing / 3, 0))
        painter.drawLine(QtCore.QPointF(wing / 3, 0), QtCore.QPointF(wing, 0))
        painter.drawEllipse(QtCore.QPointF(0, 0), 3, 3)
        painter.end()


WIDEST_READOUT = {"pitch": " -90.0°", "roll": "-180.0°", "yaw": "-180.0°", "heading": "360.0° compass"}


class AttitudePanel(QtWidgets.QGroupBox):
    """The horizon, the 3D view of the body beside it, and the readouts of one estimate."""

    def __init__(self, parent=None):
        super().__init__("Attitude", parent)  # the estimate shown named once there is one (``show_session``)
        self.indicator = AttitudeIndicator()
        self.body_view = AttitudeView3D()
        views = QtWidgets.QHBoxLayout()
        views.addWidget(self.indicator)
        views.addWidget(self.body_view)
        # Over the top of the horizon, not in the layout: appearing after a settings change (Apply) it
        # would push every panel below it down, and the user's next click would land on another field.
        self.reconverging = QtWidgets.QLabel(self.indicator)
        self.reconverging.setWordWrap(True)
        self.reconverging.setStyleSheet("background:#ffe9a8; color:#5a4000; padding:4px; border:1px solid #e0b040")
        self.reconverging.hide()
        self.readouts = {name: QtWidgets.QLabel("—") for name in ("pitch", "roll", "yaw", "heading")}
        numbers = QtWidgets.QFormLayout()
        for name, label in self.readouts.items():
            label.setAlignment(QtCore.Qt.AlignRight)
            label.setStyleSheet("font-family: monospace; font-size: 14px")
            # Wide enough for the widest reading from the start: the side column takes its width from
            # its contents when it is made, and a label that grows later would be cut ("-122.4").
            label.setMinimumWidth(label.fontMetrics().horizontalAdvance(WIDEST_READOUT[name]) + 4)
            numbers.addRow(name, label)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(views)
        # Its own height always, spare height to the panels below: the side column is re-laid out
        # whenever a label there changes, and a panel between its minimum and preferred heights
        # would take or give 50 px each time, moving everything under it (the field the user aims at).
        self.setSizePolicy(QtWidgets.QSizePolicy.Preferred, QtWidgets.QSizePolicy.Fixed)
        layout.addLayout(numbers)

    def show_session(self, session: Session, body: bool = True) -> None:
        """The newest estimate of the one ``sample_streams.headline`` names: the session's first estimator
        (AHF2 in the app's sessions; a recording's own first otherwise), or the aircraft's own when there is
        no raw IMU or it is too slow for host filtering (the title says why); ``body``: the 3D view too."""
        name, why = headline(session.view)
        self.setTitle(f"Attitude ({name.upper() if name != 'onboard' else 'onboard'}{' — ' + why if why else ''})")
        heading = heading_now(session.view)
        self.readouts["heading"].setText("—" if heading is None else f"{heading[0]:5.1f}° {heading[1]}")
        table, prefix = (session.view.onboard, "q") if name == "onboard" else (session.view.imu, f"{name}_q")
        last = table.tail(1)
        if not len(last):
            return
        self.show_reconverging(reconverging(session.view.events, float(last[0][0])))
        q = last[0][[table.columns.index(f"{prefix}{c}") for c in "wxyz"]]
        self.show_attitude(*quaternion.euler_deg(q))
        if body:
            self.body_view.set_attitude(q)

    def show_reconverging(self, restart: tuple[str, float] | None) -> None:
        if restart is None:
            self.reconverging.hide()
            return
        kind, left_s = restart
        self.reconverging.setText(f"⚠ Re-converging after {RESTART_WORDS[kind]}: the estimates may be off for {math.ceil(left_s)} s more")
        self.reconverging.setFixedWidth(self.indicator.width())
        self.reconverging.adjustSize()
        self.reconverging.show()

    def clear(self) -> None:
        """No attitude (a new session, before its first estimate)."""
        self.setTitle("Attitude")
        self.show_reconverging(None)
        self.show_attitude(math.nan, math.nan, math.nan)
        self.body_view.set_attitude(None)
        self.readouts["heading"].setText("—")

    def show_attitude(self, yaw_deg: float, pitch_deg: float, roll_deg: float) -> None:
        self.indicator.set_attitude(yaw_deg, pitch_deg, roll_deg)
        for name, value in (("pitch", pitch_deg), ("roll", roll_deg), ("yaw", yaw_deg)):
            self.readouts[name].setText("—" if math.isnan(value) else f"{value:+7.1f}°")

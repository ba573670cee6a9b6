"""A 3D view of the aircraft body: a quadrotor (X frame) turned by the estimate's quaternion, drawn
in software with ``QPainter`` (no OpenGL, so it draws under Xvfb and offscreen alike).

The camera is fixed to the earth (docs/conventions.md: NED), south of the aircraft and
``ELEVATION_DEG`` above it, looking north: yaw turns the airframe on screen, north is away from the
viewer, east to the right. The front arms and rotors are red, the rear ones grey; a grid on the
ground plane gives the horizon.
"""

from __future__ import annotations

import math

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets

from groundstation import quaternion

ELEVATION_DEG = 25.0
CAMERA_DISTANCE = 6.0  # in arm lengths: mild perspective
ARM = 1.0
ROTOR_RADIUS = 0.45
BODY = (0.35, 0.25, 0.12)  # half sizes (forward, right, down) of the central box
FRONT, REAR, BODY_COLOR, GROUND = QtGui.QColor("#d62728"), QtGui.QColor("#7f7f7f"), QtGui.QColor("#1f3b73"), QtGui.QColor("#c8c8c8")


def _rotor_ring(centre: np.ndarray, points: int = 16) -> np.ndarray:
    angle = np.linspace(0.0, 2 * math.pi, points, endpoint=False)
    return centre + ROTOR_RADIUS * np.column_stack([np.cos(angle), np.sin(angle), np.zeros(points)])


# Body-frame geometry (x forward, y right, z down). Arms at ±45° and ±135°: an X quadrotor.
ARM_TIPS = ARM * np.array([[1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0]]) / math.sqrt(2)
ROTORS = [_rotor_ring(tip) for tip in ARM_TIPS]
_fx, _fy, _fz = BODY
BOX_CORNERS = np.array([[sx * _fx, sy * _fy, sz * _fz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
BOX_FACES = ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5))
GRID = np.arange(-2.0, 2.01, 1.0)
GROUND_Z = 1.2  # the ground plane, below the aircraft (NED: down is +z)


def to_camera(points_ned: np.ndarray) -> np.ndarray:
    """NED points to camera axes (right, up, depth away from the viewer)."""
    e = math.radians(ELEVATION_DEG)
    north, east, down = points_ned[:, 0], points_ned[:, 1], points_ned[:, 2]
    up = -down
    # The camera looks north, tilted down by the elevation.
    depth = north * math.cos(e) - up * math.sin(e)
    screen_up = north * math.sin(e) + up * math.cos(e)
    return np.column_stack([east, screen_up, depth])


def project(points_ned: np.ndarray, scale: float) -> np.ndarray:
    """Camera perspective to screen pixels from the centre (x right, y down)."""
    camera = to_camera(points_ned)
    factor = scale * CAMERA_DISTANCE / (CAMERA_DISTANCE + camera[:, 2])
    return np.column_stack([camera[:, 0] * factor, -camera[:, 1] * factor])


def body_to_ned(q_wxyz: np.ndarray, points_body: np.ndarray) -> np.ndarray:
    return quaternion.rotate(np.asarray(q_wxyz, dtype=float), points_body)


class AttitudeView3D(QtWidgets.QWidget):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.q: np.ndarray | None = None  # body to NED, w first; None: unknown
        self.setMinimumSize(150, 150)
        self.setSizePolicy(QtWidgets.QSizePolicy.Expanding, QtWidgets.QSizePolicy.Fixed)
        self.setToolTip("The aircraft seen from the south, above: north is away from you, east to the right")

    def sizeHint(self) -> QtCore.QSize:
        return QtCore.QSize(200, 200)

    def set_attitude(self, q_wxyz) -> None:
        q = None if q_wxyz is None or not np.all(np.isfinite(q_wxyz)) else np.asarray(q_wxyz, dtype=float)
        if (q is None) != (self.q is None) or (q is not None and not np.array_equal(q, self.q)):
            self.q = q
            self.update()

    def paintEvent(self, event) -> None:
        painter = QtGui.QPainter(self)
        painter.setRenderHint(QtGui.QPainter.Antialiasing)
        painter.fillRect(self.rect(), QtGui.QColor("#f4f6fa"))
        painter.translate(self.width() / 2, self.height() / 2)
        scale = min(self.width(), self.height()) / 3.2
        self._draw_ground(painter, scale)
        if self.q is None:
            painter.setPen(QtGui.QColor("#666"))
            painter.drawText(QtCore.QRectF(-self.width() / 2, -10, self.width(), 20), QtCore.Qt.AlignCenter, "no attitude")
            painter.end()
            return
        # Painter's algorithm: the farthest part first.
        parts = []
        for tip, ring, colour in zip(ARM_TIPS, ROTORS, (FRONT, FRONT, REAR, REAR)):
            arm = body_to_ned(self.q, np.array([[0.0, 0.0, 0.0], tip]))
            parts.append((to_camera(arm)[:, 2].mean(), "line", arm, colour))
            disc = body_to_ned(self.q, ring)
            parts.append((to_camera(disc)[:, 2].mean(), "polygon", disc, colour))
        corners = body_to_ned(self.q, BOX_CORNERS)
        for face in BOX_FACES:
            points = corners[list(face)]
            parts.append((to_camera(points)[:, 2].mean(), "polygon", points, BODY_COLOR))
        for _, kind, points, colour in sorted(parts, key=lambda part: -part[0]):
            screen = [QtCore.QPointF(x, y) for x, y in project(points, scale)]
            if kind == "line":
                painter.setPen(QtGui.QPen(colour, 4))
                painter.drawLine(*screen)
            else:
                fill = QtGui.QColor(colour)
                fill.setAlpha(150 if colour is not BODY_COLOR else 230)
                painter.setPen(QtGui.QPen(colour.darker(130), 1))
                painter.setBrush(fill)
                painter.drawPolygon(QtGui.QPolygonF(screen))
        painter.end()

    @staticmethod
    def _draw_ground(painter: QtGui.QPainter, scale: float) -> None:
        painter.setPen(QtGui.QPen(GROUND, 1))
        for value in GRID:
            for line in (np.array([[value, GRID[0], GROUND_Z], [value, GRID[-1], GROUND_Z]]),
                         np.array([[GRID[0], value, GROUND_Z], [GRID[-1], value, GROUND_Z]])):
                a, b = project(line, scale)
                painter.drawLine(QtCore.QPointF(*a), QtCore.QPointF(*b))
        north = project(np.array([[GRID[-1] + 0.3, 0.0, GROUND_Z]]), scale)[0]
        painter.setPen(QtGui.QColor("#555"))
        painter.drawText(QtCore.QPointF(north[0] - 4, north[1]), "N")

"""A 3D view of the aircraft body: a quadrotor (X frame) turned by the estimate's quaternion, drawn
in software with ``QPainter`` (no OpenGL, so it draws under Xvfb and offscreen alike).

The camera is fixed to the earth (docs/conventions.md: NED), south of the aircraft and
``ELEVATION_DEG`` above it, looking north: yaw turns the airframe on screen, north is away from the
viewer, east to the right. The front arms and rotors are red, the rear ones grey; a grid on the
ground plane gives the horizon.
"""

from __future__ import annotations

import functools
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


def _mesh() -> tuple[np.ndarray, list[tuple[slice, str, QtGui.QColor]]]:
    """All the body points in one array, and the parts as (rows, "line" or "polygon", colour)."""
    pieces, parts, start = [], [], 0
    for tip, ring, colour in zip(ARM_TIPS, ROTORS, (FRONT, FRONT, REAR, REAR)):
        for points, kind in ((np.array([[0.0, 0.0, 0.0], tip]), "line"), (ring, "polygon")):
            pieces.append(points)
            parts.append((slice(start, start + len(points)), kind, colour))
            start += len(points)
    for face in BOX_FACES:
        pieces.append(BOX_CORNERS[list(face)])
        parts.append((slice(start, start + 4), "polygon", BODY_COLOR))
        start += 4
    return np.concatenate(pieces), parts


MESH_POINTS, MESH_PARTS = _mesh()


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


@functools.lru_cache(maxsize=4)
def ground_lines(scale: float) -> list[QtCore.QLineF]:
    """The ground grid, north-south and east-west lines, on screen (the same for every paint at a size)."""
    lines = []
    for value in GRID:
        for ends in (np.array([[value, GRID[0], GROUND_Z], [value, GRID[-1], GROUND_Z]]),
                     np.array([[GRID[0], value, GROUND_Z], [GRID[-1], value, GROUND_Z]])):
            (ax, ay), (bx, by) = project(ends, scale)
            lines.append(QtCore.QLineF(ax, ay, bx, by))
    return lines


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
        painter.setPen(QtGui.QPen(GROUND, 1))
        painter.drawLines(ground_lines(scale))
        painter.setPen(QtGui.QColor("#555"))
        north = project(np.array([[GRID[-1] + 0.3, 0.0, GROUND_Z]]), scale)[0]
        painter.drawText(QtCore.QPointF(north[0] - 4, north[1]), "N")
        if self.q is None:
            painter.drawText(QtCore.QRectF(-self.width() / 2, -self.height() / 2, self.width(), 20), QtCore.Qt.AlignCenter,
                             "no attitude")
            painter.end()
            return
        # Every point turned and projected at once; then the painter's algorithm, the farthest part first.
        ned = body_to_ned(self.q, MESH_POINTS)
        depth = to_camera(ned)[:, 2]
        screen = project(ned, scale)
        for index in np.argsort([-depth[part].sum() / (part.stop - part.start) for part, _, _ in MESH_PARTS]):
            part, kind, colour = MESH_PARTS[index]
            points = [QtCore.QPointF(x, y) for x, y in screen[part]]
            if kind == "line":
                painter.setPen(QtGui.QPen(colour, 4))
                painter.drawLine(*points)
            else:
                painter.setPen(QtGui.QPen(colour.darker(130), 1))
                painter.setBrush(colour if colour is BODY_COLOR else colour.lighter(140))  # opaque: blending costs
                painter.drawPolygon(QtGui.QPolygonF(points))
        painter.end()


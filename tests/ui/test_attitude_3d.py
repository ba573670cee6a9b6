"""The 3D view turns the airframe as the quaternion says: nose east at yaw 90°, nose up when pitched
up, right arm down when rolled right (docs/conventions.md), and draws offscreen."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from groundstation import quaternion
from groundstation.ui.attitude_3d import ARM_TIPS, AttitudeView3D, body_to_ned, project

NOSE, RIGHT = np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]])


def screen(q, point):
    return project(body_to_ned(q, point), 100.0)[0]  # x right, y down, pixels from the centre


def q_of(yaw_deg=0.0, pitch_deg=0.0, roll_deg=0.0):
    return quaternion.from_euler_zyx(*np.radians([yaw_deg, pitch_deg, roll_deg]))


def test_body_to_ned_agrees_with_scipy():
    q = q_of(30.0, -20.0, 45.0)
    oracle = Rotation.from_euler("ZYX", [30.0, -20.0, 45.0], degrees=True)  # yaw, pitch, roll: body to NED
    np.testing.assert_allclose(body_to_ned(q, ARM_TIPS), oracle.apply(ARM_TIPS), atol=1e-12)


def test_the_airframe_turns_as_the_attitude_says():
    level = screen(q_of(), NOSE)
    assert level[0] == pytest.approx(0.0) and level[1] < 0  # nose north: away from the viewer, up on screen
    assert screen(q_of(yaw_deg=90.0), NOSE)[0] > 50.0  # nose east: right
    assert screen(q_of(yaw_deg=-90.0), NOSE)[0] < -50.0
    assert screen(q_of(pitch_deg=30.0), NOSE)[1] < level[1]  # nose up: higher on screen
    right_arm = screen(q_of(roll_deg=30.0), RIGHT)
    assert right_arm[1] > 0 and screen(q_of(roll_deg=-30.0), RIGHT)[1] < 0  # right wing down when rolled right


def test_it_draws_offscreen_and_shows_when_the_attitude_is_unknown(qtbot):
    view = AttitudeView3D()
    qtbot.addWidget(view)
    view.resize(200, 200)
    view.set_attitude(None)
    blank = view.grab().toImage()
    view.set_attitude(q_of(yaw_deg=90.0))
    east = view.grab().toImage()
    view.set_attitude(q_of(yaw_deg=-90.0))
    west = view.grab().toImage()
    assert blank != east and east != west
    # The red front rotors are on the right at yaw 90° and on the left at yaw -90°.
    def red_x(image):
        xs = [x for x in range(0, 200, 2) for y in range(0, 200, 2)
              if (c := image.pixelColor(x, y)).red() > 180 and c.green() < 120 and c.blue() < 120]
        return sum(xs) / len(xs)
    assert red_x(east) > 110 > 90 > red_x(west)
    view.set_attitude([math.nan] * 4)
    assert view.q is None

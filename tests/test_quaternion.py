"""groundstation.quaternion against scipy's Rotation (an independent implementation) on random inputs."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from groundstation import quaternion as qm

rng = np.random.default_rng(20240601)
N = 500


def random_unit_quaternions(n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def to_scipy(q):
    return Rotation.from_quat(q[..., [1, 2, 3, 0]])  # scipy is scalar-last


def from_scipy(rot):
    return rot.as_quat()[..., [3, 0, 1, 2]]


def same_rotation(p, q, atol=1e-12):
    # q and -q are the same rotation.
    return np.allclose(np.abs(np.sum(p * q, axis=-1)), 1.0, atol=atol)


def test_multiply_composes_like_scipy():
    p, q = random_unit_quaternions(N), random_unit_quaternions(N)
    expected = from_scipy(to_scipy(p) * to_scipy(q))
    assert same_rotation(qm.multiply(p, q), expected)


def test_rotate_and_matrix_agree_with_scipy():
    q = random_unit_quaternions(N)
    v = rng.normal(size=(N, 3))
    expected = to_scipy(q).apply(v)
    np.testing.assert_allclose(qm.rotate(q, v), expected, atol=1e-12)
    np.testing.assert_allclose(qm.to_matrix(q), to_scipy(q).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(qm.rotate(qm.conjugate(q), expected), v, atol=1e-12)


def test_from_matrix_round_trip_including_180_degree_turns():
    q = random_unit_quaternions(N)
    # Half turns (w = 0) are where naive 1 + trace formulas divide by zero.
    q[:4] = [[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [0, 0.6, 0.8, 0]]
    back = qm.from_matrix(qm.to_matrix(q))
    assert same_rotation(back, q)
    assert np.all(back[:, 0] >= 0)


def test_euler_zyx_matches_scipy_intrinsic_ZYX():
    yaw = rng.uniform(-np.pi, np.pi, N)
    pitch = rng.uniform(-np.pi / 2 + 1e-3, np.pi / 2 - 1e-3, N)
    roll = rng.uniform(-np.pi, np.pi, N)
    expected = from_scipy(Rotation.from_euler("ZYX", np.column_stack([yaw, pitch, roll])))
    q = qm.from_euler_zyx(yaw, pitch, roll)
    assert same_rotation(q, expected)
    np.testing.assert_allclose(qm.to_euler_zyx(q), np.column_stack([yaw, pitch, roll]), atol=1e-9)


def test_pitch_nose_up_raises_the_forward_axis_in_ned():
    # Body x forward; NED z down: 30 deg nose up puts the nose at earth z = -sin(30 deg).
    q = qm.from_euler_zyx(0.0, np.radians(30.0), 0.0)
    np.testing.assert_allclose(qm.rotate(q, [1.0, 0.0, 0.0]), [np.cos(np.radians(30)), 0, -0.5], atol=1e-12)
    # 20 deg right bank (roll positive) lowers the right wing (body y): earth z = +sin(20 deg).
    q = qm.from_euler_zyx(0.0, 0.0, np.radians(20.0))
    assert qm.rotate(q, [0.0, 1.0, 0.0])[2] == pytest.approx(np.sin(np.radians(20.0)))


def test_rotation_vector_exp_and_log_match_scipy():
    axes = rng.normal(size=(N, 3))
    rv = axes / np.linalg.norm(axes, axis=1, keepdims=True) * rng.uniform(0, 3.1, size=(N, 1))  # log returns |angle| <= pi
    rv[:3] = [[0, 0, 0], [1e-7, 0, 0], [0, 3e-5, -2e-5]]  # the small-angle branch
    q = qm.from_rotation_vector(rv)
    assert same_rotation(q, from_scipy(Rotation.from_rotvec(rv)))
    np.testing.assert_allclose(qm.to_rotation_vector(q), rv, atol=1e-12)


def test_angle_between_matches_scipy_magnitude():
    p, q = random_unit_quaternions(N), random_unit_quaternions(N)
    expected = (to_scipy(p).inv() * to_scipy(q)).magnitude()
    np.testing.assert_allclose(qm.angle_between(p, q), expected, atol=1e-9)


def test_normalise_refuses_zero():
    np.testing.assert_allclose(qm.normalise([2.0, 0, 0, 0]), qm.IDENTITY)
    with pytest.raises(ValueError):
        qm.normalise([0.0, 0, 0, 0])

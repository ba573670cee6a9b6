"""The per-sample Euler helpers equal the vectorised ones of groundstation.quaternion."""

import numpy as np

from groundstation import quaternion
from groundstation.estimation.tilt import euler_of, quaternion_of


def test_scalar_euler_helpers_equal_the_quaternion_module():
    rng = np.random.default_rng(3)
    q = quaternion.normalise(rng.normal(size=(500, 4)))
    q[q[:, 0] < 0] *= -1
    ypr = quaternion.to_euler_zyx(q)
    np.testing.assert_allclose([euler_of(tuple(r)) for r in q.tolist()], ypr, atol=1e-12)
    np.testing.assert_allclose([quaternion_of(*r) for r in ypr.tolist()], quaternion.from_euler_zyx(*ypr.T), atol=1e-12)

"""The per-sample Euler helpers equal the vectorised ones of groundstation.quaternion."""

import numpy as np

from groundstation import quaternion
from groundstation.estimation.tilt import euler_of, quaternion_of, quaternion_product


def test_scalar_euler_helpers_equal_the_quaternion_module():
    rng = np.random.default_rng(3)
    q = quaternion.normalise(rng.normal(size=(500, 4)))
    q[q[:, 0] < 0] *= -1
    ypr = quaternion.to_euler_zyx(q)
    # math against NumPy (whose atan2/asin differ from libm in the last bit on some CPUs), ~10 operations per
    # angle: a few ulp, amplified near ±90° pitch by asin's 1/cos θ; 1e-12 rad (~4500 ulp) covers |cos θ| > 1e-3.
    np.testing.assert_allclose([euler_of(tuple(r)) for r in q.tolist()], ypr, atol=1e-12)
    np.testing.assert_allclose([quaternion_of(*r) for r in ypr.tolist()], quaternion.from_euler_zyx(*ypr.T), atol=1e-12)


def test_quaternion_product_is_the_array_product():
    rng = np.random.default_rng(3)
    p, q = rng.normal(size=(2, 200, 4))
    got = np.array([quaternion_product(tuple(a), tuple(b)) for a, b in zip(p.tolist(), q.tolist())])
    np.testing.assert_allclose(got, quaternion.multiply(p, q), rtol=0, atol=1e-12)

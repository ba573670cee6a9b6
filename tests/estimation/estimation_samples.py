"""Random inputs shared by the estimator tests."""

import numpy as np


def random_samples(n, seed, acc_norm_g=(0.5, 2.0)):
    """Random rates (rad/s), specific forces within the guards (g) and periods (s), whose jitter stays
    within the interval rule's limit (1.5 running intervals, base.py), as the published filters compared
    with integrate every dt whole."""
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 1.0, (n, 3))
    acc = rng.normal(0.0, 1.0, (n, 3))
    acc *= rng.uniform(*acc_norm_g, (n, 1)) / np.linalg.norm(acc, axis=1, keepdims=True)
    dt = rng.uniform(0.009, 0.011, n)
    return gyr, acc, dt


def flight_like_samples(n, seed):
    """Moderate rates and a specific force near 1 g down whose disturbance varies from calm to rough."""
    rng = np.random.default_rng(seed)
    gyr = rng.normal(0.0, 0.3, (n, 3))
    roughness = np.repeat(rng.uniform(0.0, 0.4, n // 100 + 1), 100)[:n, None]
    acc = np.array([0.0, 0.0, -1.0]) + rng.normal(0.0, 1.0, (n, 3)) * roughness
    norm = np.linalg.norm(acc, axis=1, keepdims=True)
    acc *= np.clip(norm, 0.3, 2.5) / norm  # inside the estimators' guards, so every sample is used
    dt = rng.uniform(0.008, 0.012, n)
    return gyr, acc, dt

"""Overlapping Allan deviation of a rate signal and the IEEE Std 952-1997 (annex C) read-offs.

The sensor-error analysis of seeds 002 and 003 (docs/seeds-digest.md §4). ``y`` is a rate (°/s, g,
...) sampled every ``dt_s``; its integral ``θ_k = dt Σ_{i<k} y_i`` (θ_0 = 0, n + 1 points) gives, for a
cluster of ``m`` samples (τ = m dt), the overlapping Allan variance::

    σ²(τ) = Σ_{k=0}^{n-2m} (θ_{k+2m} - 2 θ_{k+m} + θ_k)² / (2 τ² (n + 1 - 2m))

Cluster sizes are octave spaced, m = 1, 2, 4, ... up to n // 2. The noise terms of annex C and their
lines on the log-log plot, with ``y`` in units U (e.g. °/s):

- angle (velocity) random walk, white rate noise: σ(τ) = N / √τ, slope -1/2; N in U/√Hz is σ at
  τ = 1 s on that line. N² is the *two-sided* rate PSD; a datasheet's noise density (MPU-6050: total
  RMS = density · √bandwidth) is one-sided, √2 · N (``NoiseTerms.density``). As a random walk of the
  integral per √hour, 60 · N: for a gyro in °/s the angle random walk in °/√h (1 °/s/√Hz = 1 °/√s).
- bias instability (flicker): the flat floor, σ_min = √(2 ln 2 / π) B = 0.664 B.
- rate random walk: σ(τ) = K √(τ / 3), slope +1/2; K in U/√s is σ at τ = 3 s on that line.

A line is fitted only where the curve has its slope: points whose local log-log slope is within
±1/4 of it, weighted by their number of independent clusters. Only clusters of ``min_samples`` or
more samples count (the first octaves show the sampling, e.g. a discrete random walk reads
√(1 + 1/(2m²)) above K √(τ/3), 22 % at m = 1, and a real part's anti-alias filter) and of at most
``max_fraction`` of the record (longer ones hold too few clusters to tell a slope from scatter).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # σ_min / B = 0.664 (annex C)
SLOPE_TOLERANCE = 0.25  # a point belongs to a -1/2 or +1/2 line if its local slope is this close


@dataclasses.dataclass(frozen=True)
class AllanCurve:
    """σ(τ) at octave-spaced cluster times; ``clusters`` = n // m, the independent clusters behind each."""

    tau_s: np.ndarray
    adev: np.ndarray  # in the unit of the signal
    clusters: np.ndarray


@dataclasses.dataclass(frozen=True)
class NoiseTerms:
    """Annex C read-offs of one curve, in the signal's unit U; NaN where the term is not visible."""

    n_rt_hz: float  # N: σ(1 s) on the -1/2 line, U/√Hz (= U·√s); two-sided
    b: float  # B: σ_min / 0.664, U
    b_tau_s: float  # τ of the minimum
    b_is_bound: bool  # the minimum is the last point read: the floor lies beyond, B is an upper bound
    k_rt_s: float  # K: σ(3 s) on the +1/2 line, U/√s

    @property
    def density(self) -> float:
        """The one-sided noise density a datasheet quotes, U/√Hz: √2 · N."""
        return math.sqrt(2.0) * self.n_rt_hz



def allan_deviation(y, dt_s: float) -> AllanCurve:
    """Overlapping Allan deviation of ``y`` (n,) sampled every ``dt_s`` seconds (module docstring)."""
    y = np.asarray(y, dtype=float)
    if y.ndim != 1 or len(y) < 4:
        raise ValueError(f"need a 1-D signal of at least 4 samples, got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError("the signal has NaN or infinite samples")
    if not dt_s > 0:
        raise ValueError(f"dt_s must be positive, got {dt_s}")
    n = len(y)
    # The mean leaves σ unchanged (θ gains a straight line, which the second difference cancels); taking
    # it out first keeps the running sum of a signal with a large offset (a gyro bias) precise.
    theta = np.concatenate([[0.0], np.cumsum(y - y.mean())]) * dt_s
    sizes = 2 ** np.arange(int(math.log2(n // 2)) + 1)
    adev = np.empty(len(sizes))
    for i, m in enumerate(sizes):
        d = theta[2 * m :] - 2.0 * theta[m:-m] + theta[: -2 * m]
        tau = m * dt_s
        adev[i] = math.sqrt(np.dot(d, d) / (2.0 * tau * tau * len(d)))
    return AllanCurve(tau_s=sizes * dt_s, adev=adev, clusters=n // sizes)


def local_slopes(curve: AllanCurve) -> np.ndarray:
    """d log σ / d log τ at each point: central differences, one-sided at the ends; NaN where σ = 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.gradient(np.log(curve.adev), np.log(curve.tau_s))


def noise_terms(curve: AllanCurve, min_samples: int = 8, max_fraction: float = 1.0 / 8.0) -> NoiseTerms:
    """N, B and K of ``curve`` (module docstring), from the points with ``min_samples`` · dt ≤ τ ≤
    ``max_fraction`` × record."""
    dt_s = curve.tau_s[0]
    record_s = dt_s * curve.clusters[0]
    use = (curve.tau_s >= min_samples * dt_s) & (curve.tau_s <= max_fraction * record_s) & (curve.adev > 0)
    if not use.any():
        raise ValueError("no cluster time short enough to read the curve; the record is too short")
    tau, adev, weight, slope = curve.tau_s[use], curve.adev[use], curve.clusters[use], local_slopes(curve)[use]
    lowest = int(np.argmin(adev))
    before, after = np.arange(len(tau)) <= lowest, np.arange(len(tau)) >= lowest
    # log N = log σ + ½ log τ on the -1/2 line; log K = log σ - ½ log(τ / 3) on the +1/2 line.
    n_rt_hz = _line(np.log(adev) + 0.5 * np.log(tau), weight, before & (np.abs(slope + 0.5) <= SLOPE_TOLERANCE))
    k_rt_s = _line(np.log(adev) - 0.5 * np.log(tau / 3.0), weight, after & (np.abs(slope - 0.5) <= SLOPE_TOLERANCE))
    b = float(adev[lowest]) / FLICKER_FLOOR
    return NoiseTerms(n_rt_hz=n_rt_hz, b=b, b_tau_s=float(tau[lowest]), b_is_bound=lowest == len(tau) - 1, k_rt_s=k_rt_s)


def _line(log_intercepts: np.ndarray, weight: np.ndarray, on_line: np.ndarray) -> float:
    """exp of the cluster-weighted mean intercept of the points on the line; NaN if there are none."""
    if not on_line.any():
        return math.nan
    return float(np.exp(np.average(log_intercepts[on_line], weights=weight[on_line])))

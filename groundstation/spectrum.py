"""One-sided FFT amplitude spectrum of a uniformly sampled signal (seed 003's error spectra, figures 1-3).

``amplitude_spectrum(x, dt_s)`` removes the mean (``detrend="constant"``, the default), or the least-squares
line (``"linear"``), or nothing (``None``); multiplies by a Hann window (``window="hann"``) or none
(``"boxcar"``); and returns the frequencies (Hz) and the amplitudes in the signal's own unit, scaled by the
window's coherent gain so that a sine ``A sin(2π f t)`` shows a peak of ``A`` at ``f``::

    A_k = c_k |X_k| / Σ w_n,   c_k = 2 for 0 < f_k < f_Nyquist, 1 at 0 and at Nyquist

(exactly ``A`` when ``f`` falls on a bin; between bins the Hann window reads at worst 15 % low, the
rectangular 36 %). The Hann window keeps a strong low-frequency error from leaking into the high
frequencies, which matters for drift-like errors (an integrated gyro). Broadband noise of standard
deviation σ spreads over the bins: each reads about ``σ √(2 · 1.5 / N)`` with the Hann window.

Drift is the error of an integrated gyro, so for error spectra keep the default (mean removed only): a
linear detrend would hide a constant rate bias.
"""

from __future__ import annotations

import numpy as np

WINDOWS = {"hann": lambda n: np.hanning(n + 1)[:-1], "boxcar": np.ones}  # periodic Hann, as scipy's


def amplitude_spectrum(x, dt_s: float, detrend: str | None = "constant", window: str = "hann"):
    """``(freq_hz, amplitude)``, each (N // 2 + 1,), of the samples ``x`` (N,) taken every ``dt_s`` seconds."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or len(x) < 2:
        raise ValueError(f"need a 1-D signal of at least 2 samples, got shape {x.shape}")
    if not np.isfinite(x).all():
        raise ValueError(f"the signal has {np.count_nonzero(~np.isfinite(x))} NaN/Inf samples: drop or fill them first")
    if not dt_s > 0:
        raise ValueError(f"dt_s must be positive, not {dt_s!r}")
    if window not in WINDOWS:
        raise ValueError(f"unknown window {window!r}; choose from {', '.join(WINDOWS)}")
    n = len(x)
    if detrend == "constant":
        x = x - x.mean()
    elif detrend == "linear":
        t = np.arange(n)
        x = x - np.polyval(np.polyfit(t, x, 1), t)
    elif detrend is not None:
        raise ValueError(f"detrend must be 'constant', 'linear' or None, not {detrend!r}")
    w = WINDOWS[window](n)
    amplitude = np.abs(np.fft.rfft(x * w)) / w.sum()
    amplitude[1 : (n + 1) // 2] *= 2.0  # one-sided: fold the negative frequencies (not DC, not Nyquist)
    return np.fft.rfftfreq(n, dt_s), amplitude

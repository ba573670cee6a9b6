"""What a filter on the IMU would do: a host-side notch or low-pass applied to the gyro and accelerometer
before the estimators, and the attitude difference it makes.

The filters are causal second-order sections (biquads), as an autopilot runs them sample by sample
before its estimator, so their phase lag is in the result as it would be in flight. Coefficients from
R. Bristow-Johnson's "Audio EQ Cookbook" (the form ArduPilot's ``NotchFilter`` and ``LowPassFilter2p``
use), with ``ω₀ = 2π f₀ / f_s``:

- notch, bandwidth ``B`` Hz between the -3 dB points: ``Q = f₀ / B``, ``α = sin ω₀ / (2Q)``,
  ``b = (1, -2 cos ω₀, 1)``, ``a = (1 + α, -2 cos ω₀, 1 - α)``;
- low-pass (Butterworth, ``Q = 1/√2``): ``b = ((1 - cos ω₀)/2, 1 - cos ω₀, (1 - cos ω₀)/2)``, ``a`` as above,

both divided by ``a₀``. A centre above Nyquist is folded to where the tone appears at the table's rate
(``vibration.alias_hz``): on a 100 Hz table a 130 Hz rotor shows at 30 Hz, and that is what a filter on
those samples can remove.

The difference: an estimator (default the aiding one, ``estimation.AIDING_ESTIMATOR``; with the
session's settings for it where it ran) runs over the whole IMU table twice, on the raw and on the filtered samples, with no aiding in either (so only the filter
differs); the angle between the two attitudes (``quaternion.angle_between``) over the chosen range
gives RMS and maximum in degrees.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from groundstation import quaternion
from groundstation.analysis.vibration import VibrationError, alias_hz
from groundstation.estimation import AIDING_ESTIMATOR, create
from groundstation.estimation.evaluation import sample_periods_s

KINDS = ("notch", "lowpass")
IMU_GYRO = ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s")
IMU_ACCEL = ("acc_x_g", "acc_y_g", "acc_z_g")


def biquad(kind: str, frequency_hz: float, rate_hz: float, bandwidth_hz: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` (3,), ``a[0] = 1``, of a notch at ``frequency_hz`` (``bandwidth_hz`` between its -3 dB
    points, default half the centre) or a Butterworth low-pass cutting at ``frequency_hz``."""
    nyquist = rate_hz / 2.0
    if kind not in KINDS:
        raise VibrationError(f"filter kind must be one of {', '.join(KINDS)}, not {kind!r}")
    if not 0.0 < frequency_hz < nyquist:
        raise VibrationError(f"the filter's frequency must lie between 0 and {nyquist:g} Hz (Nyquist), not {frequency_hz:g}")
    w0 = 2.0 * math.pi * frequency_hz / rate_hz
    cos_w0 = math.cos(w0)
    if kind == "notch":
        bandwidth_hz = frequency_hz / 2.0 if bandwidth_hz is None else bandwidth_hz
        if not bandwidth_hz > 0.0:
            raise VibrationError(f"the notch bandwidth must be positive, not {bandwidth_hz:g} Hz")
        alpha = math.sin(w0) / (2.0 * frequency_hz / bandwidth_hz)
        b = np.array([1.0, -2.0 * cos_w0, 1.0])
    else:
        alpha = math.sin(w0) / (2.0 / math.sqrt(2.0))
        b = np.array([(1.0 - cos_w0) / 2.0, 1.0 - cos_w0, (1.0 - cos_w0) / 2.0])
    a = np.array([1.0 + alpha, -2.0 * cos_w0, 1.0 - alpha])
    return b / a[0], a / a[0]


@njit(cache=True)
def _run_biquad(b, a, x, out):  # pragma: no cover - compiled (the test compares it with scipy's lfilter)
    for j in range(x.shape[1]):
        z1 = 0.0
        z2 = 0.0
        for k in range(x.shape[0]):  # transposed direct form II
            y = b[0] * x[k, j] + z1
            z1 = b[1] * x[k, j] - a[1] * y + z2
            z2 = b[2] * x[k, j] - a[2] * y
            out[k, j] = y


def apply(b: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The biquad run causally over each column of ``x`` (n, k) from rest; starts each column at its first
    value (as if it had held it forever) so that a 1 g accelerometer does not ring at the start."""
    x = np.asarray(x, dtype=float)
    first = x[:1]
    out = np.empty_like(x)
    _run_biquad(np.asarray(b, dtype=float), np.asarray(a, dtype=float), np.ascontiguousarray(x - first), out)
    return out + first * (np.sum(b) / np.sum(a))  # the DC gain on the held first value (1 for both kinds)


def what_if(session, kind: str, frequency_hz: float, bandwidth_hz: float | None = None,
            start_s: float | None = None, end_s: float | None = None, estimator: str = AIDING_ESTIMATOR) -> dict:
    """The attitude difference a ``kind`` filter ("notch" or "lowpass") at ``frequency_hz`` on the
    session's ``imu`` table makes over [start_s, end_s]: ``{"estimator", "filter", "centre_hz" (after
    folding), "rms_deg", "max_deg", "rows"}``. VibrationError when the session has no IMU samples or the
    filter does not fit its rate."""
    imu = session.tables.get("imu", {})
    if not len(imu.get("time_s", ())):
        raise VibrationError("the what-if needs the session's IMU samples (this session has none)")
    t = imu["time_s"]
    gyr, acc = np.column_stack([imu[c] for c in IMU_GYRO]), np.column_stack([imu[c] for c in IMU_ACCEL])
    good = np.isfinite(t) & np.isfinite(gyr).all(axis=1) & np.isfinite(acc).all(axis=1)  # gap rows out
    t, gyr, acc = t[good], gyr[good], acc[good]
    dt_s = sample_periods_s(t)
    rate_hz = 1.0 / float(np.median(dt_s[dt_s > 0]))
    centre = alias_hz(frequency_hz, rate_hz)
    b, a = biquad(kind, centre, rate_hz, bandwidth_hz)
    name = estimator
    try:
        settings = session.settings_at_start.get(name)
        create(name, settings)
    except ValueError as error:
        raise VibrationError(str(error)) from None
    raw, _ = create(name, settings).run(gyr, acc, dt_s)
    filtered, _ = create(name, settings).run(apply(b, a, gyr), apply(b, a, acc), dt_s)
    start_s = t[0] if start_s is None else start_s
    end_s = t[-1] if end_s is None else end_s
    rows = (t >= start_s) & (t <= end_s)
    angle = np.degrees(quaternion.angle_between(raw[rows], filtered[rows]))
    angle = angle[np.isfinite(angle)]
    if not len(angle):
        raise VibrationError(f"no estimated attitude between {start_s:g} s and {end_s:g} s")
    return {"estimator": name, "filter": kind, "frequency_hz": float(frequency_hz), "centre_hz": float(centre),
            "bandwidth_hz": None if kind == "lowpass" else float(bandwidth_hz or centre / 2.0),
            "rms_deg": float(np.sqrt(np.mean(angle**2))), "max_deg": float(angle.max()), "rows": int(len(angle))}

"""What a filter on the IMU would do: a host-side notch or low-pass, what it removes from the spectrum, what
it costs in phase, and the attitude difference it makes where an estimator can run on the filtered data.

The filters are causal second-order sections (biquads), as an autopilot runs them sample by sample
before its estimator, so their phase lag is in the result as it would be in flight. Coefficients from
R. Bristow-Johnson's "Audio EQ Cookbook" (the form ArduPilot's ``NotchFilter`` and ``LowPassFilter2p``
use), with ``ω₀ = 2π f₀ / f_s``:

- notch, bandwidth ``B`` Hz between the -3 dB points: ``Q = f₀ / B``, ``α = sin ω₀ / (2Q)``,
  ``b = (1, -2 cos ω₀, 1)``, ``a = (1 + α, -2 cos ω₀, 1 - α)``;
- low-pass (Butterworth, ``Q = 1/√2``): ``b = ((1 - cos ω₀)/2, 1 - cos ω₀, (1 - cos ω₀)/2)``, ``a`` as above,

both divided by ``a₀``.

Only data sampled faster than twice the filter's frequency is filtered: a 54 Hz notch on a 25 Hz IMU
would act on whatever happens to alias near its folded frequency, a number with no meaning. Per sensor,
the data is the table the vibration spectrum comes from (``vibration.fastest``: a log's full-rate IMU,
bursts included); a sensor sampled too slowly is left out, and a filter no table can carry is refused.

``what_if`` says (``WhatIf``):

- the spectrum before and after: each gap-free stretch (each burst of ArduPilot's batch sampler) filtered
  on its own from its held first value, then ``vibration.spectrum`` of both; the attenuation at the peak
  is ``10 log₁₀(P_after / P_before)`` in dB over the peak's lobe (±``LOBE_BINS``), the peak the strongest
  bin of the three axes' summed density inside the filter's stop band (gain below -3 dB) above
  ``LEVEL_CUTOFF_HZ``; and the RMS above that cut-off before and after;
- the filter's frequency response (a Bode view) at the gyro data's rate:
  ``H(e^{iω}) = (b₀ + b₁e^{-iω} + b₂e^{-2iω}) / (1 + a₁e^{-iω} + a₂e^{-2iω})``, ``ω = 2π f / f_s``, in dB and
  degrees, and the phase lag at ``LAG_AT_HZ`` (10-30 Hz, where an attitude controller works): what a tuner
  weighs against the noise removed;
- the attitude difference, only where the session's ``imu`` table (the estimators' input) is itself
  sampled fast enough and is a continuous stream: an estimator (default the aiding one,
  ``estimation.AIDING_ESTIMATOR``, with the session's settings for it where it ran) runs over the whole
  IMU table twice, on the raw and on the filtered samples, with no aiding in either (so only the filter
  differs); the angle between the two attitudes (``quaternion.angle_between``) over the range gives RMS
  and maximum in degrees. Elsewhere a one-line reason says why there is none.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numba import njit

from groundstation import quaternion
from groundstation.analysis.vibration import (CONTINUOUS_SHARE, LEVEL_CUTOFF_HZ, LOBE_BINS, SENSORS, UNITS, ImuTable,
                                              Spectrum, VibrationError, coverage, fastest, imu_tables, spectrum,
                                              stretches)
from groundstation.estimation import AIDING_ESTIMATOR, create
from groundstation.estimation.evaluation import sample_periods_s

KINDS = ("notch", "lowpass")
LAG_AT_HZ = (10.0, 20.0, 30.0)  # where a multirotor's attitude loop works: the phase a filter costs there
BODE_POINTS = 120  # log-spaced from BODE_FROM_HZ to Nyquist, with LAG_AT_HZ and the filter's frequency among them
BODE_FROM_HZ = 1.0
NOTCH_BANDWIDTH_SHARE = 0.5  # a notch's default bandwidth, of its centre (ArduPilot's advice for INS_HNTCH_BW)
IMU_GYRO = ("gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s")
IMU_ACCEL = ("acc_x_g", "acc_y_g", "acc_z_g")


def carries(rate_hz: float, frequency_hz: float) -> bool:
    """Whether data sampled at ``rate_hz`` can carry a filter at ``frequency_hz``: below its Nyquist frequency
    (above it the filter would act on aliases)."""
    return frequency_hz < rate_hz / 2.0


def biquad(kind: str, frequency_hz: float, rate_hz: float, bandwidth_hz: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` (3,), ``a[0] = 1``, of a notch at ``frequency_hz`` (``bandwidth_hz`` between its -3 dB
    points, default half the centre) or a Butterworth low-pass cutting at ``frequency_hz``."""
    if kind not in KINDS:
        raise VibrationError(f"filter kind must be one of {', '.join(KINDS)}, not {kind!r}")
    if not (frequency_hz > 0.0 and carries(rate_hz, frequency_hz)):
        raise VibrationError(f"the filter's frequency must lie between 0 and {rate_hz / 2.0:g} Hz (Nyquist), not {frequency_hz:g}")
    w0 = 2.0 * math.pi * frequency_hz / rate_hz
    cos_w0 = math.cos(w0)
    if kind == "notch":
        bandwidth_hz = NOTCH_BANDWIDTH_SHARE * frequency_hz if bandwidth_hz is None else bandwidth_hz
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


def response(b: np.ndarray, a: np.ndarray, rate_hz: float, frequency_hz) -> tuple[np.ndarray, np.ndarray]:
    """``(magnitude_db, phase_deg)`` of the biquad ``(b, a)`` run at ``rate_hz`` at ``frequency_hz`` (module docstring)."""
    z = np.exp(-2j * np.pi * np.asarray(frequency_hz, dtype=float) / rate_hz)  # e^{-iω}
    h = np.polyval(np.asarray(b)[::-1], z) / np.polyval(np.asarray(a)[::-1], z)
    with np.errstate(divide="ignore"):  # a notch's zero at its centre: -inf dB
        return 20.0 * np.log10(np.abs(h)), np.degrees(np.angle(h))


@dataclasses.dataclass(frozen=True)
class Filtered:
    """One sensor's spectrum before and after the filter, on the table it came from."""

    table: str
    sensor: str
    rate_hz: float
    stretches: int  # gap-free stretches (bursts) the spectra average over
    continuous: bool  # False: the table is bursts (``vibration.coverage`` below ``CONTINUOUS_SHARE``)
    b: np.ndarray  # (3,) the filter at this table's rate
    a: np.ndarray
    before: Spectrum
    after: Spectrum
    peak_hz: float | None  # the strongest bin in the stop band; None: no bin there
    attenuation_db: float | None  # at the peak, over its lobe
    level_before: float  # RMS above LEVEL_CUTOFF_HZ of the three axes together, in UNITS[sensor]
    level_after: float

    def as_dict(self) -> dict:
        return {"table": self.table, "rate_hz": self.rate_hz, "stretches": self.stretches, "continuous": self.continuous,
                "unit": UNITS[self.sensor],
                "b": self.b.tolist(), "a": self.a.tolist(), "peak_hz": self.peak_hz, "attenuation_db": self.attenuation_db,
                "level_before": self.level_before, "level_after": self.level_after,
                "frequency_hz": self.before.frequency_hz.tolist(), "psd_before": self.before.total_psd.tolist(),
                "psd_after": self.after.total_psd.tolist()}  # fmt: skip


@dataclasses.dataclass(frozen=True)
class WhatIf:
    """What ``what_if`` finds (module docstring); ``as_dict`` for JSON, ``lines`` for text."""

    filter: str  # "notch" or "lowpass"
    frequency_hz: float
    bandwidth_hz: float | None  # the notch's; None for the low-pass
    spectra: dict[str, Filtered]  # sensor -> before and after, for the sensors sampled fast enough
    skipped: dict[str, str]  # sensor -> why it was not filtered (sampled too slowly)
    bode_rate_hz: float  # the rate the Bode view is computed at (the gyro data's, else the accelerometer's)
    bode_hz: np.ndarray  # (K,)
    magnitude_db: np.ndarray  # (K,)
    phase_deg: np.ndarray  # (K,) wrapped to ±180
    attitude: dict | None  # {"estimator", "rms_deg", "max_deg", "rows"}; None: see attitude_note
    attitude_note: str | None

    @property
    def phase_lag_deg(self) -> dict[float, float]:
        """Phase lag (degrees, positive: the output behind) at each of ``LAG_AT_HZ`` below Nyquist."""
        return {f: float(-self.phase_deg[np.flatnonzero(self.bode_hz == f)[0]]) for f in LAG_AT_HZ if f in self.bode_hz}

    def as_dict(self) -> dict:
        gain = dict(zip(self.bode_hz.tolist(), self.magnitude_db.tolist()))
        return {"filter": self.filter, "frequency_hz": self.frequency_hz, "bandwidth_hz": self.bandwidth_hz,
                "spectra": {s: f.as_dict() for s, f in self.spectra.items()}, "skipped": self.skipped,
                "bode": {"rate_hz": self.bode_rate_hz, "frequency_hz": self.bode_hz.tolist(),
                         "magnitude_db": [m if math.isfinite(m) else None for m in self.magnitude_db.tolist()],
                         "phase_deg": self.phase_deg.tolist()},
                "phase_lag_deg": {f"{f:g}": lag for f, lag in self.phase_lag_deg.items()},
                "gain_db": {f"{f:g}": gain[f] for f in self.phase_lag_deg},
                "attitude": self.attitude, "attitude_note": self.attitude_note}  # fmt: skip

    def lines(self) -> list[str]:
        width = "" if self.bandwidth_hz is None else f", bandwidth {self.bandwidth_hz:g} Hz"
        out = [f"what-if: a {self.filter} at {self.frequency_hz:g} Hz{width}"]
        for sensor, f in self.spectra.items():
            unit = UNITS[sensor]
            peak = ("no peak in its stop band" if f.peak_hz is None
                    else f"peak at {f.peak_hz:.1f} Hz {f.attenuation_db:+.1f} dB")
            runs = f"{f.stretches} {'stretches' if f.continuous else 'bursts'}"
            out.append(f"  {sensor} ('{f.table}' at {f.rate_hz:.0f} Hz, {runs}): {peak}; RMS above "
                       f"{LEVEL_CUTOFF_HZ:g} Hz {f.level_before:.3f} -> {f.level_after:.3f} {unit}")
        out += [f"  {sensor}: not filtered: {why}" for sensor, why in self.skipped.items()]
        gain = dict(zip(self.bode_hz.tolist(), self.magnitude_db.tolist()))
        lags = ", ".join(f"{lag:.1f}° at {f:g} Hz (gain {gain[f]:+.2f} dB)" for f, lag in self.phase_lag_deg.items())
        out.append(f"  the filter (run at {self.bode_rate_hz:.0f} Hz): phase lag {lags or 'none below Nyquist'}")
        if self.attitude is not None:
            a = self.attitude
            out.append(f"  attitude ({a['estimator']} on the filtered IMU): differs by {a['rms_deg']:.3f}° RMS, "
                       f"{a['max_deg']:.3f}° max over {a['rows']} samples")
        else:
            out.append(f"  attitude: {self.attitude_note}")
        return out


def what_if(session, kind: str, frequency_hz: float, bandwidth_hz: float | None = None,
            start_s: float | None = None, end_s: float | None = None, estimator: str = AIDING_ESTIMATOR) -> WhatIf:
    """A ``kind`` filter ("notch" or "lowpass") at ``frequency_hz`` on the session's IMU data over
    [start_s, end_s] (None: the data's first / last sample): ``WhatIf`` (module docstring). VibrationError
    when no table is sampled faster than twice ``frequency_hz``, or the filter or the range does not fit."""
    if kind not in KINDS:
        raise VibrationError(f"filter kind must be one of {', '.join(KINDS)}, not {kind!r}")
    if kind == "notch" and bandwidth_hz is None:
        bandwidth_hz = NOTCH_BANDWIDTH_SHARE * frequency_hz
    tables = imu_tables(session)
    if not tables:
        raise VibrationError("the what-if needs the session's IMU samples (this session has none)")
    start_s = min(float(np.nanmin(t.time_s)) for t in tables) if start_s is None else float(start_s)
    end_s = max(float(np.nanmax(t.time_s)) for t in tables) if end_s is None else float(end_s)
    spectra, skipped = {}, {}
    for sensor in SENSORS:
        table = fastest(tables, sensor, start_s, end_s)
        if table is None:
            continue
        if not carries(table.rate_hz, frequency_hz):
            skipped[sensor] = (f"'{table.table}' is sampled at {table.rate_hz:.0f} Hz, too slowly for a filter at "
                               f"{frequency_hz:g} Hz (it needs more than {2.0 * frequency_hz:g} Hz)")
            continue
        spectra[sensor] = _filtered(table, kind, frequency_hz, bandwidth_hz)
    if not spectra:
        raise VibrationError(f"a {kind} at {frequency_hz:g} Hz needs IMU data sampled faster than {2.0 * frequency_hz:g} Hz, "
                             f"and the fastest here is slower ({'; '.join(skipped.values()) or 'no IMU samples in the range'}): "
                             "it would act on aliases, a meaningless figure; a full-rate IMU log (ArduPilot INS_LOG_BAT_*, "
                             "PX4 SDLOG_PROFILE high rate) has such data")
    bode = spectra.get("gyro") or spectra["accel"]
    nyquist = bode.rate_hz / 2.0
    grid = np.geomspace(BODE_FROM_HZ, nyquist, BODE_POINTS)
    grid = np.unique(np.concatenate([grid[grid < nyquist], [f for f in (*LAG_AT_HZ, frequency_hz) if f < nyquist]]))
    magnitude_db, phase_deg = response(bode.b, bode.a, bode.rate_hz, grid)
    attitude, note = _attitude(session, tables, kind, frequency_hz, bandwidth_hz, start_s, end_s, estimator)
    return WhatIf(kind, float(frequency_hz), None if bandwidth_hz is None else float(bandwidth_hz), spectra, skipped,
                  bode.rate_hz, grid, magnitude_db, phase_deg, attitude, note)


def _filtered(table: ImuTable, kind: str, frequency_hz: float, bandwidth_hz: float | None) -> Filtered:
    """The table's spectrum before and after the filter, each gap-free stretch filtered on its own."""
    finite = np.isfinite(table.time_s) & np.isfinite(table.values).all(axis=1)
    raw = ImuTable(table.table, table.sensor, table.time_s[finite], table.values[finite])
    b, a = biquad(kind, frequency_hz, raw.rate_hz, bandwidth_hz)
    values = raw.values.copy()
    runs = stretches(raw.time_s)
    for run in runs:
        values[run] = apply(b, a, raw.values[run])
    before, after = spectrum(raw), spectrum(dataclasses.replace(raw, values=values))
    f = before.frequency_hz
    stop = (f >= LEVEL_CUTOFF_HZ) & (response(b, a, raw.rate_hz, f)[0] < -10.0 * math.log10(2.0))  # below -3 dB
    peak_hz = attenuation_db = None
    if stop.any():
        k = int(np.flatnonzero(stop)[np.argmax(before.total_psd[stop])])
        lobe = slice(max(k - LOBE_BINS, 1), k + LOBE_BINS + 1)
        peak_hz = float(f[k])
        attenuation_db = float(10.0 * math.log10(np.sum(after.total_psd[lobe]) / np.sum(before.total_psd[lobe])))
    band = f >= LEVEL_CUTOFF_HZ
    df = float(f[1])
    continuous = coverage(raw.time_s) >= CONTINUOUS_SHARE
    return Filtered(table.table, table.sensor, raw.rate_hz, len(runs), continuous, b, a, before, after, peak_hz, attenuation_db,
                    float(math.sqrt(np.sum(before.total_psd[band]) * df)), float(math.sqrt(np.sum(after.total_psd[band]) * df)))


def _attitude(session, tables: list[ImuTable], kind: str, frequency_hz: float, bandwidth_hz: float | None,
              start_s: float, end_s: float, name: str) -> tuple[dict | None, str | None]:
    """The attitude difference on the session's ``imu`` table, or None and why not."""
    imu = session.tables.get("imu", {})
    t = np.asarray(imu.get("time_s", ()), dtype=float)
    if not len(t):
        return None, "not computed: the session has no IMU samples for an estimator"
    gyr, acc = np.column_stack([imu[c] for c in IMU_GYRO]), np.column_stack([imu[c] for c in IMU_ACCEL])
    good = np.isfinite(t) & np.isfinite(gyr).all(axis=1) & np.isfinite(acc).all(axis=1)  # gap rows out
    t, gyr, acc = t[good], gyr[good], acc[good]
    rate_hz = ImuTable("imu", "gyro", t, gyr).rate_hz
    if not carries(rate_hz, frequency_hz):
        bursts = [x for x in tables if x.table != "imu" and carries(x.rate_hz, frequency_hz) and coverage(x.time_s) < CONTINUOUS_SHARE]
        faster = ("its full-rate IMU ('" + bursts[0].table + "') is logged in bursts, on which no estimator can run"
                  if bursts else "load its full-rate IMU for it (--imu fast; in the app, File > Full-rate IMU) where the log has one")
        return None, (f"not computed: the estimators' IMU runs at {rate_hz:.0f} Hz, too slowly to carry a filter at "
                      f"{frequency_hz:g} Hz; {faster}")
    try:
        settings = session.settings_at_start.get(name)
        create(name, settings)
    except ValueError as error:
        raise VibrationError(str(error)) from None
    dt_s = sample_periods_s(t)
    b, a = biquad(kind, frequency_hz, rate_hz, bandwidth_hz)
    raw, _ = create(name, settings).run(gyr, acc, dt_s)
    filtered, _ = create(name, settings).run(apply(b, a, gyr), apply(b, a, acc), dt_s)
    rows = (t >= start_s) & (t <= end_s)
    angle = np.degrees(quaternion.angle_between(raw[rows], filtered[rows]))
    angle = angle[np.isfinite(angle)]
    if not len(angle):
        raise VibrationError(f"no estimated attitude between {start_s:g} s and {end_s:g} s")
    return {"estimator": name, "rms_deg": float(np.sqrt(np.mean(angle**2))), "max_deg": float(angle.max()),
            "rows": int(len(angle))}, None

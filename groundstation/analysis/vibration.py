"""The vibration view of a session: spectra, spectrogram, peaks, levels, clipping, a notch suggestion.

One entry point, ``vibration_summary(session, start_s, end_s)``, reads any session (the project's
100 Hz ``imu`` frames, a flight log's IMU and its faster IMU tables, a dataset) and returns a
``VibrationSummary``; the CLI (``groundstation vibration``), the workbook's Vibration sheet, the
window's Vibration tab and the flight report all show that one object.

Spectra. Welch's method (Welch 1967): the signal is cut into segments of ``nperseg`` samples
overlapping by half, each has its mean removed and is multiplied by a periodic Hann window ``w``;
the one-sided power spectral density is the mean over segments of::

    P_k = c_k |Σ_n w_n x_n e^(-2πi kn/N)|² / (f_s Σ_n w_n²),   c_k = 2 but at 0 and Nyquist

in (unit)²/Hz, so that ``Σ_k P_k Δf`` is the signal's variance (Parseval). It equals
``scipy.signal.welch(x, fs, "hann", nperseg, nperseg // 2)`` (tests/analysis/test_vibration.py). A
sine of amplitude ``A`` puts ``A²/2`` of power into its main lobe (±2 bins with Hann), so the
amplitude column is ``√(2 P_k Δf_enbw)`` with the window's noise bandwidth ``Δf_enbw = f_s Σw² / (Σw)²``
(exactly ``A`` on a bin), and a peak's amplitude sums its lobe, ``√(2 Σ_lobe P_k Δf)``, which does not
read low between bins. The spectrogram is the same segments unaveraged.

A session whose rows have gaps (a lost link, a log's dropouts) is cut into uniformly sampled stretches;
segments never cross a gap, and every stretch's segments are averaged together. A log's full-rate IMU
written in bursts (ArduPilot's batch sampler: 1,024 samples at ~2 kHz, then a gap) is such a table: each
burst is a stretch, Welch's segments lie within a burst, and the spectrum is their mean over the bursts.
``coverage`` says how much of its span a table's stretches cover: below ``CONTINUOUS_SHARE`` it is bursts,
which serve a spectrum but no estimator (an estimator would integrate across the gaps).

Levels. ArduPilot's VIBE is the accelerometer's RMS above 5 Hz (its 5 Hz high-pass), in m/s²;
ArduPilot's guidance is that below 30 m/s² is normally fine, above 30 may give position-hold
problems and above 60 nearly always does (ardupilot.org, "Measuring Vibration"). The levels here are
that RMS from the spectrum, ``√(Σ_{f ≥ 5 Hz} P_k Δf)`` per axis, for the accelerometer (m/s²) and the
gyro (°/s); the log's own VIBE and clip counters are reported beside them where it has them.

Motor peaks. A peak is labelled ``motor k×`` when it lies at ``k`` times the rotor frequency: the ESC
telemetry's mean RPM / 60 where the log has it (ArduPilot ``ESC``, PX4 ``esc_status``), otherwise the
strongest peak above ``MIN_ROTOR_HZ`` whose second harmonic is among the others on the same sensor
(an unbalanced rotor shakes at 1×, a two-blade propeller's blade pass at 2×; two unrelated tones
rarely stand in that ratio). Harmonics above Nyquist are found where they alias to.

Notch. A suggestion in the autopilot's own parameters: ArduPilot's harmonic notch
(``INS_HNTCH_ENABLE/FREQ/BW/REF/MODE/HMNCS``: centre at the hover frequency, bandwidth half of it,
throttle-tracking with the hover throttle as reference when the log has motor outputs, ESC-RPM
tracking when it has ESC telemetry) and PX4's static gyro notch (``IMU_GYRO_NF0_FRQ``,
``IMU_GYRO_NF0_BW``).
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np

from groundstation.analysis.fields import message_field
from groundstation.spectrum import WINDOWS
from groundstation.units import STANDARD_GRAVITY_M_S2

hann = WINDOWS["hann"]  # the periodic Hann window, scipy's ``get_window("hann", n)``
LEVEL_CUTOFF_HZ = 5.0  # ArduPilot's VIBE high-pass: below it is flight, above it vibration
VIBE_FINE_M_S2 = 30.0  # ArduPilot's guidance on VIBE: below, normally fine
VIBE_BAD_M_S2 = 60.0  # above, nearly always a problem
RESOLUTION_HZ = 1.0  # segments of about one second: 1 Hz bins, enough to place a motor peak
MIN_SEGMENT = 32  # fewer samples than this in every stretch: no spectrum
PEAK_OVER_MEDIAN = 10.0  # a peak's density over the spectrum's median above the cut-off (10 dB)
# The least amplitude a peak must have besides (a sine's, in the sensor's unit): a still IMU's round-off
# stands far over its own noise-free median, and a tone this weak moves no attitude and needs no notch
# (an MPU-6000's gyro noise is ~0.005 °/s/√Hz, its accelerometer's ~0.004 m/s²/√Hz: 1 Hz bins sit below).
MIN_PEAK = {"gyro": 0.05, "accel": 0.05}  # °/s, m/s²
PEAKS_PER_AXIS = 4
LOBE_BINS = 3  # a peak's power is summed over ±3 bins: the Hann main lobe (±2) and a rotor's wander
HARMONIC_TOLERANCE = 0.02  # a harmonic within 2 % (or one bin) of k × the rotor frequency
# Slower than this is the flight, a hand, a car, not a rotor (20 Hz: 1,200 rpm, below any multirotor's
# hover), and a notch there would cut into the attitude controller's band: no rotor, no notch below it.
MIN_ROTOR_HZ = 20.0
MAX_HARMONIC = 4
SPECTROGRAM_COLUMNS = 400  # at most this many time columns: neighbours averaged beyond
GAP_FACTOR = 2.5  # a step longer than 2.5 sample periods is a gap (a SITL log's steps jitter by half a period)
CONTINUOUS_SHARE = 0.99  # a stream whose stretches cover less of its span is bursts (a fifo's rare dropped message is not)
SENSORS = ("gyro", "accel")
UNITS = {"gyro": "deg/s", "accel": "m/s²"}
AXES = "xyz"
# A column unit (catalogue spelling) -> (sensor, factor to the sensor's unit above).
_UNIT_FACTORS = {
    "rad/s": ("gyro", math.degrees(1.0)), "deg/s": ("gyro", 1.0), "°/s": ("gyro", 1.0),
    "g": ("accel", STANDARD_GRAVITY_M_S2), "m/s2": ("accel", 1.0), "m/s²": ("accel", 1.0), "m/s/s": ("accel", 1.0),
}  # fmt: skip
_VIBE_TABLE = re.compile(r"^vibe(?:_(\d+))?$")  # ArduPilot's VIBE, a table per IMU instance (autopilot/logtables.py)
_ESC_TABLE = re.compile(r"^esc(?:_status)?(?:_\d+)?$")  # ArduPilot's ESC (per instance), PX4's esc_status
_AXIS_COLUMN = re.compile(r"^(?P<stem>.*?)(?P<axis>[xyzXYZ])(?P<unit>_[a-z0-9_]+)?$")


@dataclasses.dataclass(frozen=True)
class ImuTable:
    """Three axes of one sensor from one table: session time (n,), values (n, 3) in ``UNITS[sensor]``."""

    table: str
    sensor: str  # "gyro" or "accel"
    time_s: np.ndarray
    values: np.ndarray

    @property
    def rate_hz(self) -> float:
        steps = np.diff(self.time_s)
        steps = steps[steps > 0]
        return float(1.0 / np.median(steps)) if len(steps) else 0.0


@dataclasses.dataclass(frozen=True)
class Spectrum:
    """Welch spectrum of one sensor's three axes."""

    table: str
    sensor: str
    unit: str  # of the signal; the density is in unit²/Hz
    rate_hz: float
    nperseg: int
    segments: int
    frequency_hz: np.ndarray  # (F,)
    psd: dict[str, np.ndarray]  # axis -> (F,) unit²/Hz
    amplitude: dict[str, np.ndarray]  # axis -> (F,) unit, a sine's amplitude on a bin
    spectrogram_t_s: np.ndarray  # (T,) session time at the middle of each column
    spectrogram_psd: np.ndarray  # (T, F) unit²/Hz, the three axes summed

    @property
    def total_psd(self) -> np.ndarray:
        return sum(self.psd.values())


@dataclasses.dataclass(frozen=True)
class Peak:
    frequency_hz: float
    amplitude: float  # in ``unit``: a sine's amplitude (its lobe's power)
    axis: str
    sensor: str
    unit: str
    label: str = ""  # "motor 1×", "motor 2× (aliased)", or ""


@dataclasses.dataclass
class VibrationSummary:
    """What ``vibration_summary`` finds; ``spectra`` keyed by sensor ("gyro", "accel")."""

    source: str  # the table(s) the spectra come from
    rate_hz: float  # the fastest of their sample rates
    start_s: float
    end_s: float
    spectra: dict[str, Spectrum]
    peaks: list[Peak]
    levels: dict[str, dict[str, float | None]]  # sensor -> axis -> RMS above LEVEL_CUTOFF_HZ in UNITS[sensor]; None: sampled too slowly
    clipping: dict | None  # the log's own counters (ArduPilot VIBE, PX4 vehicle_imu_status), None without
    motor: dict  # what the motors did: rotor_hz (from ESC rpm), throttle (0..1), their sources
    notch: dict  # {"frequency_hz", "bandwidth_hz", "ardupilot": {param: value}, "px4": {...}, "text"} or {}
    warnings: list[str]

    def as_dict(self) -> dict:
        """JSON-ready: everything but the arrays of the spectra."""
        return {
            "source": self.source, "rate_hz": self.rate_hz, "start_s": self.start_s, "end_s": self.end_s,
            "spectra": {s: {"table": sp.table, "rate_hz": sp.rate_hz, "nperseg": sp.nperseg, "segments": sp.segments,
                            "resolution_hz": float(sp.frequency_hz[1])} for s, sp in self.spectra.items()},
            "peaks": [dataclasses.asdict(p) for p in self.peaks], "levels": self.levels, "level_cutoff_hz": LEVEL_CUTOFF_HZ,
            "clipping": self.clipping, "motor": self.motor, "notch": self.notch, "warnings": self.warnings,
        }  # fmt: skip


    def lines(self) -> list[str]:
        """The summary as text lines: what ``groundstation vibration`` prints and the window's Vibration tab shows."""
        out = [f"vibration from {_hundredths(self.start_s)} s to {_hundredths(self.end_s)} s"]
        for sp in self.spectra.values():
            out.append(f"{sp.sensor}: '{sp.table}' at {sp.rate_hz:.1f} Hz, {sp.segments} segments of {sp.nperseg} samples "
                       f"({sp.frequency_hz[1]:.2f} Hz bins)")
        if self.peaks:
            out.append(f"peaks:  {'sensor':<6} {'axis':<4} {'frequency (Hz)':>14} {'amplitude':>16}  label")
            out += [f"        {p.sensor:<6} {p.axis:<4} {p.frequency_hz:>14.2f} {p.amplitude:>10.3f} {p.unit:<5}  {p.label}"
                    for p in self.peaks]
        else:
            out.append(f"peaks: none above {LEVEL_CUTOFF_HZ:g} Hz")
        for sensor, axes in self.levels.items():
            values = "  ".join(f"{a} {v:.3f}" for a, v in axes.items() if v is not None) + f" {UNITS[sensor]}"
            if None in axes.values():
                values = f"none (sampled at {self.spectra[sensor].rate_hz:.1f} Hz: nothing above {LEVEL_CUTOFF_HZ:g} Hz)"
            out.append(f"level {sensor} (RMS above {LEVEL_CUTOFF_HZ:g} Hz): {values}")
        c = self.clipping
        if c and c["source"] == "VIBE":
            for imu, e in c["imus"].items():
                out.append(f"VIBE IMU {imu}: max " + " ".join(f"{a.upper()} {e[f'max_vibe_{a}_m_s2']:.1f}" for a in AXES)
                           + f" m/s², {e['clips']} clips: {e['verdict']} (ArduPilot: fine below {VIBE_FINE_M_S2:g}, "
                           f"a problem above {VIBE_BAD_M_S2:g} m/s²)")
        elif c:
            out.append(f"{c['source']}: " + ", ".join(f"{k} {v:g}" for k, v in c.items() if k != "source"))
        if "rotor_hz" in self.motor:
            out.append(f"motors: {self.motor['rotor_hz']:.1f} Hz rotor frequency ({self.motor['rotor_source']} rpm)")
        if "throttle" in self.motor:
            out.append(f"motors: throttle {self.motor['throttle']:.3f} above idle ({self.motor['throttle_source']})")
        out.append(self.notch["text"] if self.notch else f"notch: no peak above {MIN_ROTOR_HZ:g} Hz to suggest one for")
        return out + [f"warning: {w}" for w in self.warnings]


def _hundredths(seconds: float) -> str:
    """``seconds`` to 0.01, a time a hair before zero (a full-rate IMU's first sample) as 0.00, not -0.00."""
    return f"{round(seconds, 2) + 0.0:.2f}"  # + 0.0: -0.0 becomes 0.0


class VibrationError(ValueError):
    """The time range or the session cannot give a spectrum (too few samples, no IMU)."""


# ---------------------------------------------------------------------------------------------- spectra


def segment_length(rate_hz: float, longest: int) -> int:
    """Samples per Welch segment: the power of two nearest to ``rate_hz / RESOLUTION_HZ``, no longer than
    the longest uniform stretch; VibrationError when even ``MIN_SEGMENT`` does not fit."""
    n = 2 ** max(5, round(math.log2(max(rate_hz, 1.0) / RESOLUTION_HZ)))
    while n > longest and n > MIN_SEGMENT:
        n //= 2
    if n > longest:
        raise VibrationError(f"too few samples for a spectrum: the longest gap-free stretch has {longest}, "
                             f"a spectrum needs at least {MIN_SEGMENT}")
    return n


def segment_psd(x: np.ndarray, rate_hz: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """``(starts, P)``: each half-overlapping segment's one-sided density (S, nperseg // 2 + 1) of ``x``
    (n,) or (n, k) (then P is (S, F, k)), with each segment's mean removed and the Hann window."""
    step = nperseg - nperseg // 2  # overlap nperseg // 2, as scipy's default
    starts = np.arange(0, len(x) - nperseg + 1, step)
    frames = np.stack([x[s : s + nperseg] for s in starts])  # (S, N) or (S, N, k)
    frames = frames - frames.mean(axis=1, keepdims=True)
    w = hann(nperseg).reshape((1, nperseg) + (1,) * (x.ndim - 1))
    p = np.abs(np.fft.rfft(frames * w, axis=1)) ** 2 / (rate_hz * float(np.sum(w * w)))
    p[:, 1 : -1 if nperseg % 2 == 0 else None] *= 2.0  # one-sided: fold the negative frequencies
    return starts, p


def welch(x, rate_hz: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """``(frequency_hz, psd)`` of a uniformly sampled ``x`` (n,) or (n, k): the mean of ``segment_psd``."""
    x = np.asarray(x, dtype=float)
    if len(x) < nperseg:
        raise VibrationError(f"too few samples for a spectrum: {len(x)}, a segment needs {nperseg}")
    _, p = segment_psd(x, rate_hz, nperseg)
    return np.fft.rfftfreq(nperseg, 1.0 / rate_hz), p.mean(axis=0)


def amplitude_from_psd(psd: np.ndarray, rate_hz: float, nperseg: int) -> np.ndarray:
    """A sine's amplitude on a bin from its density: ``√(2 P Δf_enbw)`` (module docstring)."""
    w = hann(nperseg)
    return np.sqrt(2.0 * psd * rate_hz * float(np.sum(w * w)) / float(np.sum(w)) ** 2)


def stretches(time_s: np.ndarray) -> list[slice]:
    """The uniformly sampled runs of ``time_s``: cut where a step is not positive or longer than
    ``GAP_FACTOR`` times the median step."""
    if len(time_s) < 2:
        return [slice(0, len(time_s))] if len(time_s) else []
    steps = np.diff(time_s)
    positive = steps[steps > 0]
    period = np.median(positive) if len(positive) else 0.0
    cuts = np.flatnonzero((steps <= 0) | (steps > GAP_FACTOR * period)) + 1
    edges = [0, *cuts.tolist(), len(time_s)]
    return [slice(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def coverage(time_s: np.ndarray) -> float:
    """The share of ``time_s``'s span that its gap-free ``stretches`` cover, each sample counting one median
    period: 1 for a continuous stream, about 0.4 for one sensor of ArduPilot's batch sampler."""
    time_s = np.asarray(time_s, dtype=float)
    time_s = time_s[np.isfinite(time_s)]
    if len(time_s) < 2:
        return 1.0
    steps = np.diff(time_s)
    period = float(np.median(steps[steps > 0])) if (steps > 0).any() else 0.0
    covered = sum(time_s[run.stop - 1] - time_s[run.start] + period for run in stretches(time_s))
    return float(min(covered / (time_s[-1] - time_s[0] + period), 1.0)) if period > 0 else 1.0


def spectrum(table: ImuTable) -> Spectrum:
    """Welch spectrum and spectrogram of one sensor's table over its gap-free stretches."""
    finite = np.isfinite(table.time_s) & np.isfinite(table.values).all(axis=1)
    t, v = table.time_s[finite], table.values[finite]
    runs = stretches(t)
    rate = ImuTable(table.table, table.sensor, t, v).rate_hz
    nperseg = segment_length(rate, max((r.stop - r.start for r in runs), default=0))
    times, powers = [], []
    for run in runs:
        if run.stop - run.start >= nperseg:
            starts, p = segment_psd(v[run], rate, nperseg)
            times.append(t[run][starts + nperseg // 2])  # the segment's middle sample
            powers.append(p)
    p = np.concatenate(powers)  # (S, F, 3)
    psd = p.mean(axis=0)
    freq = np.fft.rfftfreq(nperseg, 1.0 / rate)
    spec_t, spec_p = _columns_at_most(np.concatenate(times), p.sum(axis=2), SPECTROGRAM_COLUMNS)
    return Spectrum(table.table, table.sensor, UNITS[table.sensor], rate, nperseg, len(p), freq,
                    {a: psd[:, i] for i, a in enumerate(AXES)},
                    {a: amplitude_from_psd(psd[:, i], rate, nperseg) for i, a in enumerate(AXES)}, spec_t, spec_p)


def _columns_at_most(t: np.ndarray, p: np.ndarray, most: int) -> tuple[np.ndarray, np.ndarray]:
    """Average neighbouring spectrogram columns so that at most ``most`` remain (an image of a long log)."""
    group = max(1, math.ceil(len(t) / most))
    if group == 1:
        return t, p
    n = len(t) // group * group
    return t[:n].reshape(-1, group).mean(axis=1), p[:n].reshape(-1, group, p.shape[1]).mean(axis=1)


# ---------------------------------------------------------------------------------------------- tables


def imu_tables(session) -> list[ImuTable]:
    """Every three-axis gyro or accelerometer in the session's tables: columns that differ only in their
    axis letter, whose unit (the catalogue's) is a rate or an acceleration, named for the sensor (``gyr``,
    ``acc``) or bare ``x``/``y``/``z`` in a table so named (a log's fast IMU batches)."""
    found = []
    for info in session.catalogue:
        columns = session.tables.get(info.name, {})
        if "time_s" not in columns or not len(columns["time_s"]):
            continue
        groups: dict[tuple[str, str], dict[str, str]] = {}
        for column in info.columns:
            match = _AXIS_COLUMN.match(column.name)
            if match is None or column.unit not in _UNIT_FACTORS:
                continue
            sensor, _ = _UNIT_FACTORS[column.unit]
            named = (match["stem"] or info.name).lower()
            if ("gyr" if sensor == "gyro" else "acc") not in named:
                continue
            groups.setdefault((match["stem"], column.unit), {})[match["axis"].lower()] = column.name
        for (stem, unit), axes in groups.items():
            if set(axes) == set(AXES):
                sensor, factor = _UNIT_FACTORS[unit]
                values = np.column_stack([columns[axes[a]] for a in AXES]) * factor
                found.append(ImuTable(info.name, sensor, np.asarray(columns["time_s"], dtype=float), values))
    return found


def fastest(tables: list[ImuTable], sensor: str, start_s: float, end_s: float) -> ImuTable | None:
    """The ``sensor``'s table with the highest sample rate that has samples in [start_s, end_s]."""
    cut = [_between(t, start_s, end_s) for t in tables if t.sensor == sensor]
    cut = [t for t in cut if len(t.time_s) >= 2]
    return max(cut, key=lambda t: (t.rate_hz, t.table == "imu"), default=None)


def _between(table: ImuTable, start_s: float, end_s: float) -> ImuTable:
    keep = (table.time_s >= start_s) & (table.time_s <= end_s)
    return ImuTable(table.table, table.sensor, table.time_s[keep], table.values[keep])


def _column(columns: dict, field: str) -> np.ndarray | None:
    """A logged message's field: the column named ``field`` or ``field_<unit>`` (``fields``)."""
    return message_field(columns, field)


def _rows(session, table: str, start_s: float, end_s: float) -> dict | None:
    columns = session.tables.get(table)
    if not columns or "time_s" not in columns or not len(columns["time_s"]):
        return None
    keep = (columns["time_s"] >= start_s) & (columns["time_s"] <= end_s)
    return {name: np.asarray(values)[keep] for name, values in columns.items()} if keep.any() else None


# ---------------------------------------------------------------------------------------------- peaks


def alias_hz(frequency_hz: float, rate_hz: float) -> float:
    """Where a tone at ``frequency_hz`` appears when sampled at ``rate_hz`` (folded into 0 .. Nyquist)."""
    return abs(frequency_hz - rate_hz * round(frequency_hz / rate_hz))


def find_peaks(sp: Spectrum) -> list[Peak]:
    """The strongest local maxima of each axis's density above ``LEVEL_CUTOFF_HZ`` that stand
    ``PEAK_OVER_MEDIAN`` times over the axis's median there and reach ``MIN_PEAK``; frequency the lobe's
    power-weighted mean, amplitude from the lobe's power."""
    f = sp.frequency_hz
    df = f[1] - f[0]
    band = f >= LEVEL_CUTOFF_HZ
    peaks = []
    for axis, p in sp.psd.items():
        if band.sum() < 3:
            continue
        floor = float(np.median(p[band]))
        k = np.flatnonzero(band[1:-1] & (p[1:-1] > p[:-2]) & (p[1:-1] >= p[2:]) & (p[1:-1] > PEAK_OVER_MEDIAN * floor)) + 1
        kept: list[int] = []
        for i in k[np.argsort(p[k])[::-1]]:
            if all(abs(i - j) > LOBE_BINS for j in kept):
                kept.append(int(i))
            if len(kept) == PEAKS_PER_AXIS:
                break
        for i in kept:
            lobe = slice(max(i - LOBE_BINS, 1), min(i + LOBE_BINS + 1, len(f)))
            power = p[lobe]
            amplitude = math.sqrt(2.0 * np.sum(power) * df)
            if amplitude >= MIN_PEAK[sp.sensor]:
                peaks.append(Peak(float(np.sum(f[lobe] * power) / np.sum(power)), amplitude, axis, sp.sensor, sp.unit))
    return sorted(peaks, key=lambda q: -q.amplitude)


def label_motor_peaks(peaks: list[Peak], spectra: dict[str, Spectrum], rotor_hz: float | None) -> tuple[list[Peak], float | None]:
    """Label the peaks at k × the rotor frequency (``rotor_hz`` from ESC telemetry, else the strongest peak
    above ``MIN_ROTOR_HZ`` with its second harmonic on the same sensor); ``spectra`` per sensor, for the rate (to
    find harmonics where they alias) and the bin width. Returns the labelled peaks and the rotor
    frequency used (None: no motor family found)."""
    source = "ESC rpm"
    if rotor_hz is None:
        source = ""
        for candidate in (p for p in peaks if p.frequency_hz >= MIN_ROTOR_HZ):  # strongest first
            family = _harmonics(peaks, candidate.frequency_hz, spectra)
            if any(k == 2 and peaks[i].sensor == candidate.sensor for i, k in family.items()):
                rotor_hz = candidate.frequency_hz
                break
    if rotor_hz is None:
        return peaks, None
    family = _harmonics(peaks, rotor_hz, spectra)
    labelled = []
    for i, p in enumerate(peaks):
        if i in family:
            k = family[i]
            aliased = k * rotor_hz > spectra[p.sensor].rate_hz / 2.0
            extra = ", ".join(x for x in (source, "aliased" if aliased else "") if x)
            p = dataclasses.replace(p, label=f"motor {k}×" + (f" ({extra})" if extra else ""))
        labelled.append(p)
    return labelled, rotor_hz


def _harmonics(peaks: list[Peak], rotor_hz: float, spectra: dict[str, Spectrum]) -> dict[int, int]:
    """peak index -> harmonic number k for the peaks within tolerance of k × ``rotor_hz`` (or its alias)."""
    out = {}
    for i, p in enumerate(peaks):
        sp = spectra[p.sensor]
        resolution = float(sp.frequency_hz[1])  # one bin
        for k in range(1, MAX_HARMONIC + 1):
            expected = alias_hz(k * rotor_hz, sp.rate_hz)
            if abs(p.frequency_hz - expected) <= max(HARMONIC_TOLERANCE * k * rotor_hz, resolution):
                out[i] = k
                break
    return out


# ---------------------------------------------------------------------------------------------- log counters


def clipping(session, start_s: float, end_s: float) -> dict | None:
    """The log's own vibration and clip counters over the range: ArduPilot's ``VIBE`` (per IMU instance,
    tables ``vibe``, ``vibe_1`` ...: the largest VibeX/Y/Z in m/s² and the clips added, ``Clip`` or ``Clip0..2``), PX4's
    ``vehicle_imu_status`` (accelerometer clips added, vibration metrics)."""
    instances = sorted((int(m[1] or 0), name) for name in session.tables if (m := _VIBE_TABLE.match(name)))
    if instances:
        out = {"source": "VIBE", "guidance_m_s2": {"fine_below": VIBE_FINE_M_S2, "bad_above": VIBE_BAD_M_S2}, "imus": {}}
        for imu, name in instances:
            vibe = _rows(session, name, start_s, end_s)
            if vibe is None:
                continue
            entry = {f"max_vibe_{a}_m_s2": float(np.nanmax(_column(vibe, f"Vibe{a.upper()}"))) for a in AXES}
            clips = [c for c in (_column(vibe, "Clip"), *(_column(vibe, f"Clip{j}") for j in range(3))) if c is not None]
            entry["clips"] = int(sum(np.nanmax(c) - np.nanmin(c) for c in clips))  # counters since boot: what the range added
            entry["verdict"] = vibe_verdict(max(entry[f"max_vibe_{a}_m_s2"] for a in AXES))
            out["imus"][str(imu)] = entry
        return out
    status = _rows(session, "vehicle_imu_status", start_s, end_s)
    if status is not None:
        clips = [c for j in range(3) if (c := _column(status, f"accel_clipping[{j}]")) is not None
                 or (c := _column(status, f"accel_clipping_{j}")) is not None]
        out = {"source": "vehicle_imu_status", "clips": int(sum(np.nanmax(c) - np.nanmin(c) for c in clips))}
        for metric in ("accel_vibration_metric", "gyro_vibration_metric"):
            values = _column(status, metric)
            if values is not None:
                out[f"max_{metric}"] = float(np.nanmax(values))
        return out
    return None


def vibe_verdict(level_m_s2: float) -> str:
    """ArduPilot's guidance on a VIBE level (m/s²)."""
    if level_m_s2 < VIBE_FINE_M_S2:
        return "fine"
    return "may cause problems" if level_m_s2 < VIBE_BAD_M_S2 else "too high"


def motor_state(session, start_s: float, end_s: float) -> dict:
    """The motors over the range, where logged: ``rotor_hz`` (mean ESC RPM / 60 over every ESC: ArduPilot
    ``ESC`` tables ``esc_0`` ..., PX4 ``esc_status``) and ``throttle`` (0..1, mean over the active outputs while above idle: ArduPilot
    ``RCOU`` PWM 1000-2000 µs, PX4 ``actuator_outputs``)."""
    out: dict = {}
    esc = [name for name in session.tables if _ESC_TABLE.match(name)]
    rpm = [np.asarray(v, dtype=float) for name in esc if (rows := _rows(session, name, start_s, end_s)) is not None
           for column, v in rows.items() if "rpm" in column.lower()]
    rpm = np.concatenate(rpm) if rpm else np.zeros(0)
    rpm = rpm[np.isfinite(rpm) & (rpm > 0)]
    if len(rpm):
        out.update(rotor_hz=float(rpm.mean() / 60.0), rotor_source=", ".join(esc))
    for table, pattern in (("rcou", re.compile(r"^C\d+(_|$)")), ("actuator_outputs", re.compile(r"^output[_\[]?\d+"))):
        rows = _rows(session, table, start_s, end_s)
        if rows is None:
            continue
        pwm = np.column_stack([np.asarray(v, dtype=float) for n, v in rows.items() if pattern.match(n)] or [np.zeros(0)])
        active = np.nanmax(pwm, axis=0) > 1000.0 if pwm.size else np.zeros(0, dtype=bool)  # motors that ran
        if active.any():
            throttle = np.clip((pwm[:, active] - 1000.0) / 1000.0, 0.0, 1.0).mean(axis=1)
            flying = throttle[throttle > 0.05]
            if len(flying):
                out.update(throttle=float(flying.mean()), throttle_source=table)
                break
    return out


# ---------------------------------------------------------------------------------------------- notch


def notch_suggestion(peaks: list[Peak], rotor_hz: float | None, motor: dict) -> dict:
    """The notch for the rotor fundamental (else the strongest gyro peak above ``MIN_ROTOR_HZ``, else the
    strongest peak there), in ArduPilot's and PX4's parameters; {} without one. Bandwidth half the centre (ArduPilot's advice for
    INS_HNTCH_BW); harmonics ``HMNCS`` a bitmask of the motor harmonics found (bit k-1 for k×)."""
    if rotor_hz is not None:
        centre = rotor_hz
    else:
        fast = [p for p in peaks if p.frequency_hz >= MIN_ROTOR_HZ]
        gyro = [p for p in fast if p.sensor == "gyro"]
        if not (gyro or fast):
            return {}
        centre = (gyro or fast)[0].frequency_hz
    centre = round(centre, 1)
    bandwidth = round(centre / 2.0, 1)
    harmonics = {int(p.label.split()[1].rstrip("×")) for p in peaks if p.label.startswith("motor ")} or {1}
    mode, reference = 0, 0.0  # fixed
    if "rotor_source" in motor:
        mode, reference = 3, 1.0  # ESC telemetry: the frequency follows each motor's RPM
    elif "throttle" in motor:
        mode, reference = 1, round(motor["throttle"], 3)  # throttle: f = FREQ √(throttle / REF)
    ardupilot = {"INS_HNTCH_ENABLE": 1, "INS_HNTCH_FREQ": centre, "INS_HNTCH_BW": bandwidth, "INS_HNTCH_REF": reference,
                 "INS_HNTCH_MODE": mode, "INS_HNTCH_HMNCS": sum(1 << (k - 1) for k in sorted(harmonics))}
    px4 = {"IMU_GYRO_NF0_FRQ": centre, "IMU_GYRO_NF0_BW": bandwidth}
    text = (f"notch at {centre:g} Hz, bandwidth {bandwidth:g} Hz. ArduPilot: "
            + ", ".join(f"{k}={v:g}" for k, v in ardupilot.items()) + ". PX4: " + ", ".join(f"{k}={v:g}" for k, v in px4.items()))
    return {"frequency_hz": centre, "bandwidth_hz": bandwidth, "ardupilot": ardupilot, "px4": px4, "text": text}


# ---------------------------------------------------------------------------------------------- summary


def vibration_summary(session, start_s: float | None = None, end_s: float | None = None) -> VibrationSummary:
    """The vibration view of ``session`` (a ``session.product.SessionData``, or anything with its
    ``tables`` and ``catalogue``) between session times ``start_s`` and ``end_s`` (None: its first /
    last sample).

    For each sensor (gyro in °/s, accelerometer in m/s²) the fastest table that has it in the range
    (``imu_tables``: the project's ``imu``, a log's faster IMU batches) gives a Welch spectrum and
    spectrogram (``Spectrum``); then the peaks (``find_peaks``) with motor harmonics labelled
    (``label_motor_peaks``, against ESC RPM where logged), the levels (RMS above ``LEVEL_CUTOFF_HZ``),
    the log's clip counters (``clipping``), what the motors did (``motor_state``) and a notch suggestion
    (``notch_suggestion``). VibrationError (a ValueError) for a reversed range or too few samples."""
    tables = imu_tables(session)
    if not tables:
        raise VibrationError("the session has no gyro or accelerometer samples")
    first = min(float(np.nanmin(t.time_s)) for t in tables)
    last = max(float(np.nanmax(t.time_s)) for t in tables)
    start_s = first if start_s is None else float(start_s)
    end_s = last if end_s is None else float(end_s)
    if not start_s < end_s:
        raise VibrationError(f"the range must start before it ends (from {start_s:g} s to {end_s:g} s)")
    spectra = {}
    for sensor in SENSORS:
        table = fastest(tables, sensor, start_s, end_s)
        if table is not None:
            spectra[sensor] = spectrum(table)
    if not spectra:
        raise VibrationError(f"no IMU samples between {start_s:g} s and {end_s:g} s (the session runs {first:g} to {last:g} s)")
    warnings = []
    rates = {s: sp.rate_hz for s, sp in spectra.items()}
    for sp in spectra.values():
        if sp.rate_hz < 2.0 * 100.0:  # a multirotor's motors turn at 100 Hz and more
            warnings.append(f"{sp.sensor} from '{sp.table}' at {sp.rate_hz:.0f} Hz: motor vibration above "
                            f"{sp.rate_hz / 2:.0f} Hz shows aliased; a faster IMU log (ArduPilot INS_LOG_BAT_*, PX4 "
                            "SDLOG_PROFILE high rate) shows it where it is")
    motor = motor_state(session, start_s, end_s)
    peaks = [p for sp in spectra.values() for p in find_peaks(sp)]
    peaks.sort(key=lambda p: (SENSORS.index(p.sensor), -p.amplitude))
    peaks, rotor_hz = label_motor_peaks(peaks, spectra, motor.get("rotor_hz"))
    levels = {}
    for sensor, sp in spectra.items():
        band = sp.frequency_hz >= LEVEL_CUTOFF_HZ
        df = sp.frequency_hz[1]
        fast_enough = sp.rate_hz / 2.0 > LEVEL_CUTOFF_HZ
        levels[sensor] = {a: float(math.sqrt(np.sum(sp.psd[a][band]) * df)) if fast_enough else None for a in AXES}
    source = ", ".join(dict.fromkeys(sp.table for sp in spectra.values()))
    return VibrationSummary(source, max(rates.values()), start_s, end_s, spectra, peaks, levels,
                            clipping(session, start_s, end_s), motor, notch_suggestion(peaks, rotor_hz, motor), warnings)

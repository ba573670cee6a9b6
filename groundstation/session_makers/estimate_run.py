"""The host estimators over a session's samples, run forward a stretch at a time (the batch path's
estimator stage, ``session_makers.batch``).

``EstimateRun`` holds what the estimators are fed (each sample's gyro, accelerometer, interval and aiding,
in body axes and physical units) and where their run breaks (a recorded settings change, a device restart),
and runs them from the first sample in stretches of at most ``STRETCH_SAMPLES``, each estimator's state
carried from one stretch to the next: ``Estimator.run`` is ``step`` in a loop, so where a stretch ends
changes no number (tests/session/test_estimate_run.py). Each run starts from a fresh ``EstimatorBank``
and repeats the breaks, so the run can be made again: whole, it fills the ``imu`` table once; for an
export its columns are made a stretch at a time and never held whole (``Streamed``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np

from groundstation.session_parts.estimators import EstimatorBank
from groundstation.session.product import estimate_columns

# What one stretch holds: 10 estimators' columns over it are ~9 MB (65,536 samples made the 1 h open's peak 20 MB
# higher for no less CPU: bench/bench_export_memory.out.md)
STRETCH_SAMPLES = 16_384
STREAMED_STRETCH_SAMPLES = 16_384  # ``Streamed``'s: held beside the writer's stretch of rows


@dataclasses.dataclass(frozen=True)
class Break:
    """Before sample ``sample``: a recorded settings change (``event``) or, when ``event`` is None, a
    device restart or clock jump (``EstimatorBank.restart``)."""

    sample: int
    event: dict | None


@dataclasses.dataclass
class EstimateRun:
    filters: tuple[str, ...]
    settings: dict
    forced: dict | None
    aiding: str | None
    gyr_rad_s: np.ndarray | SampleColumns  # (n, 3) as measured: for the estimators that estimate their own gyro bias
    # the rest bias (``RestBiasCalibrator``) and the first sample it is removed from, for the others; None: none
    bias: tuple[int, tuple[float, float, float]] | None
    acc_g: np.ndarray | SampleColumns  # (n, 3)
    dt_s: np.ndarray  # (n,)
    mag_uT: np.ndarray | SparseRows | None  # (n, 3) the reading each sample hands the estimators, NaN for none
    gps: np.ndarray | SparseRows | None  # (n, 4) likewise
    breaks: list[Break]  # in sample order

    def __len__(self) -> int:
        return len(self.dt_s)

    def stretches(self, names=None, stretch_samples: int | None = None) -> Iterator[tuple[int, int, dict]]:
        """``(start, end, {name: (q, diagnostics)})`` for consecutive stretches of samples from the first to
        the last, at most ``stretch_samples`` each (default ``STRETCH_SAMPLES``), each estimator of ``names``
        (default: all) run over it as the session ran it."""
        names = self.filters if names is None else tuple(names)
        stretch_samples = stretch_samples or STRETCH_SAMPLES
        bank = EstimatorBank(self.filters, self.settings, self.forced, self.aiding)
        bounds = sorted({0, *(b.sample for b in self.breaks), *range(0, len(self), stretch_samples)})
        pending = iter(self.breaks)
        upcoming = next(pending, None)
        for start, end in zip(bounds, bounds[1:] + [len(self)]):
            while upcoming is not None and upcoming.sample <= start:
                if upcoming.event is None:
                    bank.restart()
                else:
                    bank.change(upcoming.event["name"], upcoming.event.get("settings", {}))
                upcoming = next(pending, None)
            if end <= start:
                continue
            out = {}
            gyr = self.gyr_rad_s[start:end]
            unbiased = self._unbiased(gyr, start, end)
            # the stretch's inputs read once for every estimator (each a copy: ``SampleColumns``, ``SparseRows``)
            acc, dt = self.acc_g[start:end], self.dt_s[start:end]
            mag = None if self.mag_uT is None else self.mag_uT[start:end]
            gps = None if self.gps is None else self.gps[start:end]
            for name in names:
                estimator = bank.estimators[name]
                q, diagnostics = estimator.run(gyr if estimator.estimates_gyro_bias else unbiased, acc, dt, mag, gps)
                bank.last_q[name] = tuple(q[-1].tolist())
                out[name] = (q, diagnostics)
            yield start, end, out

    def _unbiased(self, gyr: np.ndarray, start: int, end: int) -> np.ndarray:
        """``gyr``, samples ``start:end``, with the rest bias removed from where it was measured."""
        if self.bias is None or self.bias[0] >= end:
            return gyr
        first, bias = self.bias
        unbiased = gyr.copy()
        unbiased[max(first - start, 0):] -= np.array(bias)
        return unbiased


class SampleColumns:
    """Columns of a table on its sample rows, read a stretch at a time as an (n, k) array's rows would be
    (``[start:end]``, a copy): the estimators' inputs read from the ``imu`` table instead of kept twice."""

    def __init__(self, table: np.ndarray, sample_rows: np.ndarray, columns: list[int]):
        self._table, self._sample_rows, self._columns = table, sample_rows, columns

    def __getitem__(self, rows: slice) -> np.ndarray:
        at = self._sample_rows[rows]
        if len(at) and at[-1] - at[0] == len(at) - 1:  # consecutive rows (no gap row among them): a block copy
            return self._table[at[0]:at[-1] + 1, self._columns]
        return self._table[at[:, None], self._columns]


class SparseRows:
    """An (n, k) array whose rows are mostly NaN (the aiding readings handed to the samples: a magnetometer
    reading every few samples, a GPS fix every twenty), held as the rows that are not, and read a stretch at
    a time as the array's rows would be (``[start:end]``, a copy)."""

    def __init__(self, rows: np.ndarray):
        rows = np.asarray(rows, dtype=float)
        self._shape = rows.shape
        self._at = np.flatnonzero(~np.isnan(rows).all(axis=1))
        self._values = rows[self._at]

    def __len__(self) -> int:
        return self._shape[0]

    def __getitem__(self, rows: slice) -> np.ndarray:
        start, stop, _ = rows.indices(self._shape[0])
        out = np.full((max(stop - start, 0), self._shape[1]), np.nan)
        first, last = np.searchsorted(self._at, (start, stop))
        out[self._at[first:last] - start] = self._values[first:last]
        return out


class Streamed:
    """The ``imu`` table's columns of the estimators ``names``, not held: made for the rows an export asks,
    in order (``SessionData.estimates``). ``sample_rows``: the table row of each sample (the others are
    gap rows, NaN)."""

    def __init__(self, run: EstimateRun, names: tuple[str, ...], sample_rows: np.ndarray, columns: tuple[str, ...]):
        self.names = names
        self.columns = columns  # their imu columns, in the catalogue's order (``catalogue.estimator_columns``)
        self._sample_rows = sample_rows
        self._stretches = run.stretches(names, STREAMED_STRETCH_SAMPLES)
        self._held: tuple[int, int, dict] = (0, 0, {})
        self._next_row = 0

    def at(self, rows: np.ndarray, columns: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
        """The streamed ``columns`` (default: every one) at table ``rows`` (ascending, after every row asked
        before: the run only goes forward); NaN on the gap rows."""
        rows = np.asarray(rows, dtype=np.int64)
        if len(rows) and rows[0] < self._next_row:
            raise ValueError("the streamed estimates go forward only: rows were asked again or out of order")
        sample = np.searchsorted(self._sample_rows, rows)
        is_sample = sample < len(self._sample_rows)
        is_sample[is_sample] = self._sample_rows[sample[is_sample]] == rows[is_sample]
        out = {c: np.full(len(rows), np.nan) for c in (self.columns if columns is None else columns)}
        wanted = np.flatnonzero(is_sample)
        while len(wanted):
            start, end, values = self._held
            here = wanted[(sample[wanted] >= start) & (sample[wanted] < end)]
            for name, (q, diagnostics) in values.items():
                for column, values_of in estimate_columns(name, q, diagnostics).items():
                    if column in out:
                        out[column][here] = values_of[sample[here] - start]
            wanted = wanted[sample[wanted] >= end]
            if len(wanted):
                self._held = next(self._stretches)
        if len(rows):
            self._next_row = int(rows[-1]) + 1
        return out

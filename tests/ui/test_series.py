"""The plot buffers: full resolution for the recent window, min/max bins for older samples, gaps."""

import threading

import numpy as np

from groundstation.session.table import Table
from groundstation.ui.series import BIN_ROWS, RECENT_S, Series


def test_old_samples_become_min_max_bins_and_recent_ones_stay_exact():
    table = Table(("time_s", "v"))
    series = Series(table, lambda rows, columns: {"v": rows[:, 1]})
    t = np.arange(0, 1500.0, 0.01)
    t[t > 700.0] += 2.0  # the port was away for 2 s
    v = np.sin(t) + np.random.default_rng(1).normal(0, 0.1, len(t))
    for part in np.array_split(np.column_stack([t, v]), 40):
        table.append(part.ravel().tolist())
        series.take(threading.Lock())
    recent_t, recent_v = series.data("v", 600.0)
    window = t >= t[-1] - 600.0
    assert np.array_equal(recent_t[1:], t[window]) and np.array_equal(recent_v[1:], v[window].astype(np.float32))
    older_t, older_v = series.older("v", None)
    newer_t, _ = series.data("v", None)
    assert older_t[0] == 0.0 and newer_t[-1] == t[-1] and older_t[-1] < newer_t[0]
    # The gap holds a row of NaN in its middle (no line across it, issue 24), binned like a restart's.
    after = int(np.searchsorted(t, 702.0, side="right"))
    tb = np.insert(t, after, (t[after - 1] + t[after]) / 2)
    vb = np.insert(v, after, np.nan)
    assert len(older_t) == 2 * np.sum(tb < newer_t[0]) // BIN_ROWS  # 10 samples -> 2 points
    bins = vb[: len(older_t) // 2 * BIN_ROWS].reshape(-1, BIN_ROWS).astype(np.float32)
    broken = np.isnan(bins).any(axis=1)
    assert broken.sum() == 1 and np.isnan(older_v[0::2][broken]).all() and np.isnan(older_v[1::2][broken]).all()
    assert np.array_equal(older_v[0::2][~broken], bins[~broken].min(axis=1))
    assert np.array_equal(older_v[1::2][~broken], bins[~broken].max(axis=1))
    assert series.recent.time_s[0] >= t[-1] - 2 * RECENT_S  # binned as it went, not at the end
    assert series.gaps == [(t[t <= 702.0][-1], t[t > 702.0][0])]
    assert series.value_at("v", t[-1]) == np.float32(v[-1])


def test_a_restart_gap_row_still_breaks_the_line_once_binned():
    """The pipeline writes a row of NaN (all but time) where the device restarted; once those rows are
    old enough to be binned, the bin holding it must stay NaN, or the older curve joins the restart."""
    table = Table(("time_s", "v", "w"))
    series = Series(table, lambda rows, columns: {"v": rows[:, 1], "w": rows[:, 2]})
    t = np.arange(0, 1500.0, 0.01)
    v = np.cos(t)
    w = np.where(np.arange(len(t)) % 2, np.nan, 1.0)  # a quantity only every other row: no gap
    reset = np.searchsorted(t, 300.0)
    rows = np.column_stack([t, v, w])
    rows[reset, 1:] = np.nan  # the pipeline's gap row
    for part in np.array_split(rows, 40):
        table.append(part.ravel().tolist())
        series.take(threading.Lock())
    older_t, older_v = series.older("v", None)
    assert older_t[-1] > 300.0
    broken = np.flatnonzero(np.isnan(older_v))
    assert older_t[broken].min() <= 300.0 <= older_t[broken].max()  # the bin of the restart is NaN
    assert len(broken) == 2  # that bin's two points only
    _, older_w = series.older("w", None)
    assert np.isnan(older_w).sum() == 2  # a quantity missing in some rows keeps its bins, except the restart's

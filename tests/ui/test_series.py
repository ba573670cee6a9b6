"""The plot buffers: full resolution for the recent window, min/max bins for older samples, gaps."""

import threading

import numpy as np

from groundstation.session_parts.table import LIVE_CHUNK_ROWS, LIVE_KEEP_ROWS, Table
from groundstation.ui.series import HISTORY_BINS, RECENT_S, Series, per_pixel


def assert_bins_hold_min_max(older_t, older_v, t, v):
    """Each bin of the history, (first time, min), (last time, max), holds the minimum and maximum of
    the samples between its times, and the bins cover the samples before the recent ones."""
    starts = np.searchsorted(t, older_t[0::2])
    ends = np.searchsorted(t, older_t[1::2], side="right")
    assert starts[0] == 0 and np.array_equal(starts[1:], ends[:-1])  # contiguous, nothing left out
    covered = v[: ends[-1]].astype(np.float32)
    low = np.minimum.reduceat(covered, starts)
    high = np.maximum.reduceat(covered, starts)
    assert np.array_equal(older_v[0::2], low, equal_nan=True) and np.array_equal(older_v[1::2], high, equal_nan=True)


def feed(series, table, rows, parts):
    for part in np.array_split(rows, parts):
        table.append(part.ravel().tolist())
        series.take(threading.Lock())


def test_the_history_stays_within_its_bound_over_hours_and_looks_the_same():
    """Five hours at 100 Hz (far beyond the bound): the series holds at most RECENT_S of samples and
    2 x HISTORY_BINS history points; every bin still holds its samples' minimum and maximum, and a
    whole-session plot 1000 pixels wide shows each pixel's column of the raw samples, give or take a
    neighbouring pixel (where a bin straddles two)."""
    table = Table(("time_s", "v"))
    series = Series(table, lambda rows, columns: {"v": rows[:, 1]})
    t = np.arange(0, 5 * 3600.0, 0.01)
    v = np.sin(t / 50.0) + np.random.default_rng(2).normal(0, 0.1, len(t))
    feed(series, table, np.column_stack([t, v]), 300)
    assert series.history.count <= 2 * HISTORY_BINS
    assert series.recent.count <= RECENT_S * 100 * 1.6  # the recent buffer grows by half its size at most once over
    older_t, older_v = series.older("v", None)
    assert_bins_hold_min_max(older_t, older_v, t, v)
    recent_t, recent_v = series.data("v", None)
    drawn_t, drawn_v = np.concatenate([older_t, recent_t]), np.concatenate([older_v, recent_v])
    pixels = np.linspace(0, t[-1], 1001)
    raw_px = np.clip(np.searchsorted(pixels, t, side="right") - 1, 0, 999)
    drawn_px = np.clip(np.searchsorted(pixels, drawn_t, side="right") - 1, 0, 999)
    def envelope(px, values):
        low, high = np.full(1000, np.inf), np.full(1000, -np.inf)
        np.minimum.at(low, px, values)
        np.maximum.at(high, px, values)
        return low, high
    raw_low, raw_high = envelope(raw_px, v.astype(np.float32))
    low, high = envelope(drawn_px, drawn_v)
    def widened(values, op):
        padded = np.concatenate([[values[0]], values, [values[-1]]])
        return op(op(padded[:-2], padded[1:-1]), padded[2:])
    assert np.all(low >= widened(raw_low, np.minimum)) and np.all(high <= widened(raw_high, np.maximum))
    assert np.all(raw_low >= widened(low, np.minimum)) and np.all(raw_high <= widened(high, np.maximum))


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
    # The gap holds a row of NaN in its middle (no line across it, issue 24): its bin's min and max are NaN.
    after = int(np.searchsorted(t, 702.0, side="right"))
    tb = np.insert(t, after, (t[after - 1] + t[after]) / 2)
    vb = np.insert(v, after, np.nan)
    assert_bins_hold_min_max(older_t, older_v, tb, vb)
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


def test_a_slow_series_is_a_line_and_its_own_long_pauses_are_its_gaps():
    """A tlog's GPS_RAW_INT and SYS_STATUS come at 2 Hz (the shared ArduSub tlog): each 0.5 s interval was taken
    for a gap (GAP_S), a NaN row put in each, and the Flight tab's GPS and Battery pages drew no line at all
    (issue 34). A gap is a pause long for the series' own rate; a pause of 5 s still is one, fed whole or a row
    at a time as a live link feeds it."""
    t = np.arange(0.0, 60.0, 0.5) + np.random.default_rng(2).uniform(-0.1, 0.1, 120)  # 2 Hz, arrival jitter
    t[t > 30.0] += 5.0  # the link was away for 5 s
    rows = np.column_stack([t, np.sin(t)])
    for parts in (1, len(t)):
        table = Table(("time_s", "v"))
        series = Series(table, lambda rows, columns: {"v": rows[:, 1]})
        feed(series, table, rows, parts)
        drawn_t, drawn_v = series.data("v", None)
        assert series.gaps == [(t[t <= 35.0][-1], t[t > 35.0][0])]
        assert np.isnan(drawn_v).sum() == 1 and len(drawn_t) == len(t) + 1


def test_per_pixel_keeps_what_every_sample_draws_in_each_pixel_column():
    """Against the samples undecimated: in each pixel column the same lowest and highest value, the same
    first and last sample (the lines to the neighbouring columns), every NaN (a gap's break), in time order;
    at most four samples a column besides the NaN."""
    rng = np.random.default_rng(35)
    t = np.cumsum(rng.uniform(0.005, 0.015, 20_000))
    values = np.cumsum(rng.normal(0.0, 1.0, len(t))).astype(np.float32)
    values[rng.choice(len(t), 40, replace=False)] = np.nan
    left_s, pixel_s = t[0] - 0.37, 0.8
    keep = per_pixel(t, values, left_s, pixel_s)
    assert np.all(np.diff(keep) > 0)
    column, kept_column = np.floor((t - left_s) / pixel_s), np.floor((t[keep] - left_s) / pixel_s)
    for c in np.unique(column):
        every, kept = values[column == c], values[keep][kept_column == c]
        assert np.nanmin(every) == np.nanmin(kept) and np.nanmax(every) == np.nanmax(kept)
        assert t[column == c][0] == t[keep][kept_column == c][0] and t[column == c][-1] == t[keep][kept_column == c][-1]
        assert np.count_nonzero(np.isnan(kept)) == np.count_nonzero(np.isnan(every))
    assert len(keep) <= 4 * (len(np.unique(column)) + 2 * 40) and len(keep) < len(t) / 10


def test_a_series_holds_no_more_after_its_ten_minutes():
    """A plot series of a live session (issue 35: the app's RSS grew from 10 to 20 minutes): once 10 minutes
    (the longest window) have passed, 20 minutes hold the same bytes: its recent buffer is sized for
    ``RECENT_S`` at the series' pace and its history for its bound (they grew by half at 10.4 minutes, and at
    each merge of the history)."""
    table = Table(("time_s", "v"), keep_rows=LIVE_KEEP_ROWS, chunk_rows=LIVE_CHUNK_ROWS)
    series = Series(table, lambda rows, columns: {"v": rows[:, 1], "w": -rows[:, 1]})
    lock = threading.Lock()
    held = []
    for second in range(20 * 60):
        for i in range(100):
            table.append((second + i / 100.0, np.sin(second + i / 100.0)))
        series.take(lock)
        if second >= 10 * 60:
            held.append(series.nbytes())
    assert series.history.count > 0 and min(held) == max(held)

"""The stacked plots on synthetic tables: the crosshair readout never moves the plots, a curve
switched on from outside repaints its legend entry, "Resume view" follows at once, a window longer
than the session starts at 0, the onboard curve lies beneath the estimators'."""

import threading

import numpy as np
import pytest
from PySide6 import QtCore, QtGui

from groundstation.session_parts.table import Table
from groundstation.estimation import ESTIMATORS, live_estimators
from groundstation.estimation import colour_of as colour
from groundstation.palette import ONBOARD_COLOUR, PALETTE
from groundstation.ui.live_view import attitude_plots, diagnostic_plots
from groundstation.ui.plots import Curve, Plot, StackedPlots
from groundstation.ui.series import Series
from tests.waiting import LIMIT_MS

FILTERS = ("ahf", "hf", "ecf", "hfm", "ecfm", "mcf", "ukf", "sssrukf")


def series_until(end_s: float, filters=FILTERS) -> dict[str, Series]:
    """Pitch and roll of every estimator, and the onboard ones, at 100 Hz up to ``end_s``."""
    t = np.arange(0.0, end_s, 0.01)
    quantities = [f"{n}_{a}_deg" for n in filters for a in ("pitch", "roll")]
    imu = Table(("time_s", *quantities))
    imu.append(np.column_stack([t] + [np.sin(t + i) * 10 for i in range(len(quantities))]).ravel().tolist())
    onboard = Table(("time_s", "onboard_pitch_deg", "onboard_roll_deg"))
    onboard.append(np.column_stack([t, np.cos(t), np.sin(t)]).ravel().tolist())

    def columns(rows, names):
        return {name: rows[:, i] for i, name in enumerate(names) if name != "time_s"}

    series = {"imu": Series(imu, columns), "onboard": Series(onboard, columns)}
    for s in series.values():
        s.take(threading.Lock())
    return series


@pytest.fixture
def plots(qtbot):
    widget = StackedPlots(attitude_plots(FILTERS))
    qtbot.addWidget(widget)
    widget.resize(900, 600)
    widget.show()
    qtbot.waitExposed(widget)
    return widget


def x_range(plots):
    return tuple(plots.items[0].getViewBox().viewRange()[0])


def test_a_long_crosshair_readout_never_changes_the_plot_geometry(plots, qtbot):
    series = series_until(240.0)
    plots.draw(series, 30.0, None)
    qtbot.wait(50)
    before = [item.sceneBoundingRect() for item in plots.items]
    middle = plots.items[0].sceneBoundingRect().center()
    plots.scene().sigMouseMoved.emit(middle)  # every estimator shown: a long readout
    text = plots.readout.text
    assert "SSSRUKF" in (text() if callable(text) else text)
    qtbot.wait(50)
    plots.draw(series, 30.0, None)
    qtbot.wait(50)
    assert [item.sceneBoundingRect() for item in plots.items] == before
    assert x_range(plots)[1] >= 240.0  # the newest data still in view


def test_a_curve_switched_on_from_outside_repaints_its_legend_entry(qtbot):
    plots = StackedPlots(attitude_plots(FILTERS), hidden=frozenset({"HF"}))
    qtbot.addWidget(plots)
    plots.show()
    qtbot.waitExposed(plots)
    sample = next(s for s, label in plots.legend.items if label.text == "HF")
    painted = []
    paint = sample.paint
    sample.paint = lambda *args: (painted.append(sample.item.isVisible()), paint(*args))
    qtbot.wait(100)
    painted.clear()
    plots.set_visible("HF", True)  # the Estimators panel's check box
    qtbot.waitUntil(lambda: True in painted, timeout=LIMIT_MS)  # the entry drawn as shown


def test_resume_view_follows_the_newest_data_at_once(plots):
    series = series_until(200.0)
    plots.draw(series, 600.0, None)
    following = x_range(plots)
    plots.items[0].setXRange(20.0, 25.0, padding=0)  # the user zoomed while the view was paused
    plots.draw(series, 600.0, None)  # "Resume view": the next draw
    assert x_range(plots) == pytest.approx(following)


def test_a_window_longer_than_the_session_shows_from_zero(plots):
    plots.draw(series_until(42.0), 600.0, None)
    assert x_range(plots) == pytest.approx((0.0, 600.0))
    plots.draw(series_until(700.0), 600.0, None)
    low, high = x_range(plots)
    assert high >= 700.0 and high - low == pytest.approx(600.0)


def test_the_onboard_curve_lies_beneath_the_estimators_and_is_dashed(plots):
    onboard = next(c for s, c in plots.curves if s.label == "onboard")
    ahf = next(c for s, c in plots.curves if s.label == "AHF")
    assert onboard.zValue() < ahf.zValue()
    assert onboard.opts["pen"].style() == QtCore.Qt.DashLine


def test_every_estimator_has_its_own_colour_from_one_colour_blind_safe_palette():
    shown = [ONBOARD_COLOUR, *(colour(n) for n in live_estimators())]  # every estimator a live session runs
    assert len(set(shown)) == len(shown)
    assert {cls.colour for cls in ESTIMATORS.values()} <= set(PALETTE)  # each names one of the palette's


def test_a_dimensionless_axis_carries_no_unit_or_scale_factor(qtbot):
    plots = StackedPlots(diagnostic_plots())
    qtbot.addWidget(plots)
    axis = plots.items[1].getAxis("left")
    axis.setScale(1.0)
    plots.items[1].setYRange(0.0, 0.002)
    plots.show()
    qtbot.waitExposed(plots)
    qtbot.wait(50)
    assert axis.labelString().find("(1)") < 0 and "x0.001" not in axis.labelString()


def growing_series(end_s: float) -> tuple[Table, dict[str, Series]]:
    """One estimator's pitch at 100 Hz up to ``end_s``, in a table the test goes on appending to."""
    imu = Table(("time_s", "ahf_pitch_deg", "ahf_roll_deg"))
    series = {"imu": Series(imu, lambda rows, names: {n: rows[:, i] for i, n in enumerate(names) if n != "time_s"})}
    append(imu, series, 0.0, end_s)
    return imu, series


def append(table: Table, series: dict[str, Series], start_s: float, end_s: float, gap_at_s: float | None = None) -> None:
    t = np.round(np.arange(start_s, end_s - 1e-9, 0.01), 6)
    pitch = np.sin(t) * 10
    pitch[np.isclose(t, gap_at_s or -1.0)] = np.nan  # a restart's gap row
    table.append(np.column_stack([t, pitch, np.cos(t)]).ravel().tolist())
    for s in series.values():
        s.take(threading.Lock())


def test_frames_add_only_the_newest_samples_and_a_stopped_series_is_drawn_whole(qtbot):
    """A frame hands the curves nothing: the newest samples go to the plot's heads (a narrow strip to
    repaint), joined to the curves; every sample is drawn once; a series that stops is drawn whole."""
    plots = StackedPlots(attitude_plots(("ahf",)))
    qtbot.addWidget(plots)
    plots.resize(900, 600)
    plots.show()
    qtbot.waitExposed(plots)
    table, series = growing_series(41.0)  # the time axis shows 14..44 s: no step in these frames
    plots.draw(series, 30.0, None)
    pitch = next(c for s, c in plots.curves if s.quantity == "ahf_pitch_deg")
    before = pitch.xData
    for frame in range(20):  # 0.6 s of frames, 3 rows each; one of them a gap row
        append(table, series, 41.0 + 0.03 * frame, 41.0 + 0.03 * (frame + 1), gap_at_s=41.2)
        plots.draw(series, 30.0, {"imu"})
    assert pitch.xData is before  # the curve was not set again
    t, values = plots.drawn(pitch)
    expected_t, expected = series["imu"].data("ahf_pitch_deg", 30.0)
    np.testing.assert_array_equal(t[-len(expected_t) :], expected_t)  # each sample once, in order, up to the newest
    np.testing.assert_array_equal(values[-len(expected) :], expected)
    heads = plots.heads[0]
    strip = heads.mapRectToScene(heads.boundingRect()).width()
    assert 0 < strip < 0.05 * plots.items[0].getViewBox().sceneBoundingRect().width()
    index = next(i for i, (s, _) in enumerate(plots.curves) if s.quantity == "ahf_pitch_deg")
    path = heads.path(index)
    lines = [(path.elementAt(i - 1).x, path.elementAt(i).x) for i in range(1, path.elementCount())
             if path.elementAt(i).type == QtGui.QPainterPath.ElementType.LineToElement]
    assert lines and not [(a, b) for a, b in lines if a < 41.2 < b]  # broken at the gap row
    assert plots.stale  # nothing grew, but the heads hold samples: the next tick draws
    plots.draw(series, 30.0, set())
    assert not plots.stale and not heads.pending
    np.testing.assert_array_equal(pitch.xData, expected_t)  # the curve took its head's samples
    _, restarted = growing_series(41.9)  # a replay restarted by a seek: new series, ending just after the curve
    plots.draw(restarted, 30.0, {"imu"})
    assert not heads.pending  # nothing joined to the previous series' curve
    np.testing.assert_array_equal(pitch.xData, restarted["imu"].data("ahf_pitch_deg", 30.0)[0])


def test_the_readout_sits_beside_the_cursor_and_leaves_gaps_blank(plots, qtbot):
    """Not a band across the tops of the curves, no "+nan" over a gap (issue 24, defect 10)."""
    series = series_until(60.0, FILTERS[:2])
    plots.draw(series, 30.0, None)
    qtbot.wait(50)
    view = plots.items[0].getViewBox()
    for t_s in (35.0, 58.0):  # mid-plot, then near the right edge: the box goes to the cursor's left
        scene = view.mapViewToScene(QtCore.QPointF(t_s, 0.0))
        plots.scene().sigMouseMoved.emit(scene)
        cursor = plots.mapFromScene(scene)
        box = plots.readout.geometry()
        assert plots.readout.isVisible() and not box.adjusted(-4, -4, 4, 4).contains(cursor)
        assert box.width() < plots.width() / 2 and plots.rect().contains(box)
        assert (box.left() > cursor.x()) == (t_s == 35.0)
    gap = series_until(60.0, FILTERS[:2])
    table = gap["imu"].recent.values["ahf_pitch_deg"]
    table[3000:3100] = np.nan  # 30 s to 31 s: no AHF pitch (a gap row's NaN)
    plots.draw(gap, 30.0, None)
    text = plots.read_at(30.5)
    assert "nan" not in text.lower() and "AHF" in text  # its roll is still read


def test_the_time_axis_stays_in_seconds_after_twenty_minutes(plots, qtbot):
    """Issue 34: after 20 min the axis read "time (ks)" with ticks 1.170 ... 1.195."""
    axis = plots.items[-1].getAxis("bottom")
    plots.items[-1].setXRange(1170.0, 1195.0)
    plots.show()
    qtbot.waitExposed(plots)
    qtbot.waitUntil(lambda: "(s)" in axis.labelString(), timeout=5000)
    assert "ks" not in axis.labelString() and axis.scale == 1.0


def test_a_click_on_a_legend_name_toggles_its_curves(plots, qtbot):
    """Issue 34: on a flight log, clicks on the legend's names did nothing (only the small line before
    each name toggled): a person clicks the name."""
    from pyqtgraph.Qt import QtTest

    plots.show()
    qtbot.waitExposed(plots)
    _, text = next((s, t) for s, t in plots.legend.items if t.text == "HF")
    curve = next(c for s, c in plots.curves if s.label == "HF")
    shown = curve.isVisible()
    centre = plots.mapFromScene(text.mapToScene(text.boundingRect().center()))
    QtTest.QTest.mouseClick(plots.viewport(), QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, centre)
    qtbot.waitUntil(lambda: curve.isVisible() != shown, timeout=5000)


def test_a_flat_lines_axis_has_a_readable_range_around_it(qtbot):
    """A SITL log's HDOP is 1.21 throughout (issue 34, the Flight tab's GPS page) and its current 0 A: an axis of
    ±1.5e-7 around the line had no tick label. It gets a tenth of the value each side, at least ±0.15."""
    table = Table(("time_s", "hdop", "current_A"))
    t = np.arange(0.0, 20.0, 0.2)
    table.append(np.column_stack([t, np.full(len(t), 1.21), np.zeros(len(t))]).ravel().tolist())
    series = {"imu": Series(table, lambda rows, names: {n: rows[:, i] for i, n in enumerate(names) if n != "time_s"})}
    series["imu"].take(threading.Lock())
    plots = StackedPlots((Plot("HDOP", "", (Curve("imu", "hdop", "HDOP", "#000000"),)),
                          Plot("current", "A", (Curve("imu", "current_A", "current", "#000000"),))))
    qtbot.addWidget(plots)
    plots.resize(600, 400)
    plots.show()
    qtbot.waitExposed(plots)
    plots.draw(series, None, None)
    (low, high), (zero_low, zero_high) = (item.getViewBox().viewRange()[1] for item in plots.items)
    assert low < 1.21 < high and high - low >= 0.2
    assert zero_low <= 0 <= zero_high and zero_high - zero_low >= 0.3


def test_the_readout_follows_a_pan_under_a_still_cursor(plots, qtbot):
    """Issue 34, the tour's defect 6: the arrow keys pan a paused view under a cursor that does not move; the
    crosshair and its numbers are then those of the time now under the cursor, not the time before the pan."""
    series = series_until(60.0, FILTERS[:2])
    plots.draw(series, 30.0, None)
    qtbot.wait(50)
    view = plots.items[0].getViewBox()
    scene = view.mapViewToScene(QtCore.QPointF(45.0, 0.0))
    plots.scene().sigMouseMoved.emit(scene)
    before = plots.readout.text()
    low, high = view.viewRange()[0]
    plots.items[0].setXRange(low - 10.0, high - 10.0, padding=0)  # what ``LiveView.pan`` does
    t_s = view.mapSceneToView(scene).x()
    assert t_s == pytest.approx(35.0, abs=0.5)
    assert plots.crosshair[0].value() == pytest.approx(t_s)
    assert plots.readout.isVisible() and plots.readout.text() == plots.read_at(t_s) != before


def test_the_heading_tab_plots_only_the_estimators_whose_yaw_is_a_heading():
    """Issue 34, the tour's defect 4: AHF2's yaw, gyro-only, ran 360° -> 325° against the onboard heading's
    235° on a PX4 hop. Only estimators that take the magnetometer or the GPS velocity have a heading."""
    from groundstation import estimation
    from groundstation.estimation.evaluation import uses_magnetometer
    from groundstation.ui.live_view import heading_plots

    (plot,) = heading_plots(FILTERS)
    estimators = [c.label for c in plot.curves if c.series == "imu"]
    expected = [n for n in FILTERS if uses_magnetometer(n) or "gps" in estimation.ESTIMATORS.about(n).needs]
    assert estimators == [estimation.label(n) for n in expected] and "AHF2" not in estimators and "HF" not in estimators
    assert {c.label for c in plot.curves if c.series != "imu"} == {"compass", "GPS", "onboard"}

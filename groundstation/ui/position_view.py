"""The Position tab: the GPS track on a map of equal axes, height over time, the newest fix in numbers.

The track (east right, north up, metres from the first fix) is the whole session, with the fused
position's when the session has one and a dot at the newest fix, thinned by a stride to at most
``MAX_TRACK_POINTS``; older than ``series.RECENT_S`` it runs through the corners of its bins' boxes
(the minima and maxima of ``series.BIN_ROWS`` samples). The track and the numbers (from the newest
GPS row, float64, not the plotted float32) are set after every ``TRACK_EVERY_S`` of new samples
(the fused position comes at the IMU rate). The track's axes, equal in scale, change only when the
track leaves them or shrinks well inside them (``plots.refit``): re-ranging on every update would
repaint the whole plot. Height (GPS, barometer, fused) is a ``StackedPlots`` plot on the live
view's time window.

A fused position integrated from an IMU too slow for the host estimators (an autopilot's RAW_IMU at 4 Hz
in a tlog drifts kilometres) is not shown, and a line says why (``set_fused_absent``).
"""

from __future__ import annotations

import math

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from groundstation.autopilot.imu_rate import MIN_FILTER_RATE_HZ
from groundstation.ui.navigation import fix_name, newest_row
from groundstation.ui.plots import Curve, Plot, StackedPlots, refit
from groundstation.ui.series import Series

MAX_TRACK_POINTS = 5000
MIN_TRACK_SPAN_M = 10.0  # the track's axes show at least this much
TRACK_EVERY_S = 0.2  # of session time between track updates
COLORS = {"gps": "#1f5fbf", "baro": "#e07000", "position": "#2a9d3a"}
LABELS = {"gps": "GPS", "baro": "barometer", "position": "fused"}
FIELDS = ("latitude", "longitude", "altitude (MSL)", "height (barometer)", "ground speed", "satellites", "fix")
NO_GPS = "No GPS solution in this session (yet): the height is the barometer's."


def no_fused_text(imu_hz: float) -> str:
    return (f"No fused position: the IMU arrives at {imu_hz:.1f} Hz, too slowly for the host estimators (needs "
            f">= {MIN_FILTER_RATE_HZ:.0f} Hz); the track is the GPS's.")


def height_plot() -> Plot:
    return Plot("height", "m", tuple(Curve(name, f"{prefix}_height_m", LABELS[name], COLORS[name])
                                     for name, prefix in (("gps", "gps"), ("baro", "baro"), ("position", "fused"))))


def track_points(series: Series, prefix: str) -> tuple[np.ndarray, np.ndarray]:
    """(east, north) of the whole session, at most ``MAX_TRACK_POINTS``, the newest point kept."""
    parts = [getter(f"{prefix}_{axis}_m", None)[1] for axis in ("east", "north") for getter in (series.older, series.data)]
    east, north = np.concatenate(parts[:2]), np.concatenate(parts[2:])
    step = math.ceil(len(east) / MAX_TRACK_POINTS)
    if step > 1:
        keep = np.r_[np.arange(0, len(east) - 1, step), len(east) - 1]
        east, north = east[keep], north[keep]
    return east, north


def number(value: float | None, fmt: str, unit: str = "") -> str:
    return "—" if value is None or not math.isfinite(value) else f"{value:{fmt}}{unit}"


class PositionView(QtWidgets.QWidget):
    userInteracted = QtCore.Signal()  # the user panned or zoomed a plot

    def __init__(self, parent=None, fused_absent_hz: float | None = None):
        super().__init__(parent)
        self.track_widget = pg.PlotWidget(background="w")
        track = self.track_widget.getPlotItem()
        track.setAspectLocked(True)  # a metre north as long as a metre east
        track.disableAutoRange()  # ``_fit_track`` ranges it
        track.getViewBox().sigRangeChangedManually.connect(self.userInteracted)
        track.showGrid(x=True, y=True, alpha=0.2)
        track.setLabel("bottom", "east", units="m")
        track.setLabel("left", "north", units="m")
        self.track_legend = track.addLegend(offset=(10, 10), labelTextColor="#222")
        self.tracks = {name: track.plot(pen=pg.mkPen(COLORS[name], width=1), name=f"{LABELS[name]} track", connect="finite")
                       for name in ("gps", "position")}
        self.here = track.plot(pen=None, symbol="o", symbolSize=8, symbolBrush=COLORS["gps"], symbolPen=None)
        self.height = StackedPlots((height_plot(),))
        self.height.userInteracted.connect(self.userInteracted)
        self._drawn_s = -math.inf  # the newest position sample shown on the track and in numbers
        self.protocol: str | None = None  # the session's link: how its GPS numbers fix types
        self._fused_listed = True
        self._list_fused(False)
        self.note = QtWidgets.QLabel(NO_GPS)
        self.note.setWordWrap(True)
        self.fused_note = QtWidgets.QLabel()
        self.fused_note.setWordWrap(True)
        self.fused_note.hide()
        self._fused_absent_hz: float | None = None
        self.set_fused_absent(fused_absent_hz)
        self.readouts = {name: QtWidgets.QLabel("—") for name in FIELDS}
        numbers = QtWidgets.QFormLayout()
        numbers.addRow(self.note)
        numbers.addRow(self.fused_note)
        for name, label in self.readouts.items():
            label.setStyleSheet("font-family: monospace")
            numbers.addRow(name, label)
        right = QtWidgets.QVBoxLayout()
        right.addWidget(self.height, 1)
        right.addLayout(numbers)
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.track_widget, 1)
        layout.addLayout(right, 1)

    def clear_data(self) -> None:
        self.height.clear_data()
        for curve in (*self.tracks.values(), self.here):
            curve.setData([], [])
        self._drawn_s = -math.inf
        for label in self.readouts.values():
            label.setText("—")
        self.note.show()

    def set_fused_absent(self, imu_hz: float | None) -> None:
        """No fused position drawn while the IMU is too slow for it (``imu_hz``: its rate; None: fast enough)."""
        if (imu_hz is None) == (self._fused_absent_hz is None) and (imu_hz is None or f"{imu_hz:.1f}" == f"{self._fused_absent_hz:.1f}"):
            return
        self._fused_absent_hz = imu_hz
        self.fused_note.setVisible(imu_hz is not None)
        if imu_hz is not None:
            self.fused_note.setText(no_fused_text(imu_hz))
            self.tracks["position"].setData([], [])
            next(curve for spec, curve in self.height.curves if spec.series == "position").setData([], [])
        self._drawn_s = -math.inf  # drawn again whole

    @property
    def stale(self) -> bool:
        return self.height.stale  # as ``StackedPlots.stale``

    def draw(self, series: dict[str, Series], window_s: float | None, grew: set[str] | None) -> None:
        """As ``StackedPlots.draw`` (everything when ``grew`` is None); the track and the numbers
        after ``TRACK_EVERY_S`` more of position samples; no fused position while ``set_fused_absent``."""
        if self._fused_absent_hz is not None:
            series = {name: s for name, s in series.items() if name != "position"}
        self._list_fused("position" in series)
        self.height.draw(series, window_s, grew)
        ends = [s.end_s for name in ("gps", "baro", "position") if (s := series.get(name)) and s.end_s is not None]
        if not ends or grew is not None and max(ends) - self._drawn_s < TRACK_EVERY_S:
            return
        self._drawn_s = max(ends)
        for name, prefix in (("gps", "gps"), ("position", "fused")):
            if name in series:
                east, north = track_points(series[name], prefix)
                self.tracks[name].setData(east, north)
                if name == "gps":
                    self.here.setData(east[-1:], north[-1:])
        self._fit_track()
        self._show_numbers(series)

    def _fit_track(self) -> None:
        drawn = [(c.xData, c.yData) for c in self.tracks.values() if c.xData is not None]
        east, north = (np.concatenate([d[axis] for d in drawn] or [np.empty(0)]) for axis in (0, 1))
        east, north = (v[np.isfinite(v)] for v in (east, north))  # solutions without a fix are NaN
        if not len(east) or not len(north):
            return
        bounds = [(float(v.min()), float(v.max())) for v in (east, north)]
        span = max(max(high - low for low, high in bounds), MIN_TRACK_SPAN_M)
        view = self.track_widget.getPlotItem().getViewBox()
        ranges = [refit(low, high, shown, span) for (low, high), shown in zip(bounds, view.viewRange())]
        if any(r is not None for r in ranges):
            east, north = (r or shown for r, shown in zip(ranges, view.viewRange()))
            view.setRange(xRange=east, yRange=north, padding=0)

    def _list_fused(self, present: bool) -> None:
        """The fused position in the legends only when the session has one."""
        if present == self._fused_listed:
            return
        self._fused_listed = present
        fused_height = next(curve for spec, curve in self.height.curves if spec.series == "position")
        for legend, curve, name in ((self.track_legend, self.tracks["position"], f"{LABELS['position']} track"),
                                    (self.height.legend, fused_height, LABELS["position"])):
            if present:
                legend.addItem(curve, name)
            else:
                legend.removeItem(curve)

    def _show_numbers(self, series: dict[str, Series]) -> None:
        gps = newest_row(series["gps"].table) if "gps" in series else None
        baro = series.get("baro")
        self.note.setVisible(gps is None)
        gps = gps or {}
        self.readouts["latitude"].setText(number(gps.get("lat_deg"), ".7f", "°"))
        self.readouts["longitude"].setText(number(gps.get("lon_deg"), ".7f", "°"))
        self.readouts["altitude (MSL)"].setText(number(gps.get("alt_m"), ".1f", " m"))
        self.readouts["height (barometer)"].setText(
            number(baro.value_at("baro_height_m", baro.end_s) if baro and baro.end_s is not None else None, ".1f", " m"))
        speed = math.hypot(gps["vel_n_m_s"], gps["vel_e_m_s"]) if gps else None
        self.readouts["ground speed"].setText(number(speed, ".1f", " m/s"))
        self.readouts["satellites"].setText(number(gps.get("satellites"), ".0f"))
        self.readouts["fix"].setText(fix_name(gps["fix_type"], self.protocol) if gps else "—")

"""Stacked time plots on one shared time axis, fed from ``Series`` buffers.

Each curve is created once and updated with ``setData`` only when its series grew (or the window
changed); peak downsampling and clipping to the view keep long windows cheap. The legend on the
top plot toggles a curve on every plot that carries the same label. A crosshair follows the mouse
and reads every visible curve at the nearest sample under it.
"""

from __future__ import annotations

from dataclasses import dataclass

import pyqtgraph as pg
from PySide6 import QtCore

from groundstation.ui.series import Series


@dataclass(frozen=True)
class Curve:
    series: str  # which Series: "imu" or "onboard"
    quantity: str  # a key of that Series' values
    label: str  # legend entry; curves sharing it are toggled together
    color: str
    dashed: bool = False


@dataclass(frozen=True)
class Plot:
    title: str
    unit: str
    curves: tuple[Curve, ...]


class StackedPlots(pg.GraphicsLayoutWidget):
    """``hidden``: labels whose curves start switched off (shown greyed in the legend)."""

    userInteracted = QtCore.Signal()  # the user panned or zoomed: the caller stops following

    def __init__(self, plots: tuple[Plot, ...], hidden: frozenset[str] = frozenset(), parent=None):
        super().__init__(parent)
        self.setBackground("w")
        self.items: list[pg.PlotItem] = []
        self._stale = True  # a curve was switched on: it needs its data even if nothing grew
        self._series: dict[str, Series] = {}  # as last drawn, for the crosshair
        self._specs = plots
        self.curves: list[tuple[Curve, pg.PlotDataItem]] = []
        for row, spec in enumerate(plots):
            item = self.addPlot(row=row, col=0)
            item.setLabel("left", f"{spec.title} ({spec.unit})")
            item.showGrid(x=True, y=True, alpha=0.25)
            item.setDownsampling(auto=True, mode="peak")
            item.setClipToView(True)
            item.setAutoVisible(y=True)  # the y range follows what is in the time window
            item.getViewBox().sigRangeChangedManually.connect(self.userInteracted)
            if self.items:
                item.setXLink(self.items[0])
            if row == 0:
                item.addLegend(offset=(-10, 10), colCount=len(spec.curves), labelTextColor="#222")
            for spec_curve in spec.curves:
                pen = pg.mkPen(spec_curve.color, width=1.5, style=QtCore.Qt.DashLine if spec_curve.dashed else QtCore.Qt.SolidLine)
                curve = item.plot(pen=pen, name=spec_curve.label if row == 0 else None)
                curve.setVisible(spec_curve.label not in hidden)
                self.curves.append((spec_curve, curve))
            self.items.append(item)
        self.items[-1].setLabel("bottom", "time", units="s")
        self.crosshair = [pg.InfiniteLine(angle=90, movable=False, pen=pg.mkPen("#555", style=QtCore.Qt.DotLine))
                          for _ in self.items]
        for item, line in zip(self.items, self.crosshair):
            item.addItem(line, ignoreBounds=True)
            line.hide()
        self.readout = self.addLabel("", row=len(plots), col=0, justify="left", color="#222")
        self.scene().sigMouseMoved.connect(self._mouse_moved)
        for spec_curve, curve in self.curves:  # the top plot's legend drives the others
            if curve.name() is not None:
                curve.visibleChanged.connect(lambda c=curve, label=spec_curve.label: self._mirror(label, c.isVisible()))

    def _mirror(self, label: str, visible: bool) -> None:
        for spec, curve in self.curves:
            if spec.label == label and curve.isVisible() != visible:
                curve.setVisible(visible)
        self._stale = True

    def visible_labels(self) -> set[str]:
        return {spec.label for spec, curve in self.curves if curve.isVisible()}

    def set_visible(self, label: str, visible: bool) -> None:
        self._mirror(label, visible)

    def clear_data(self) -> None:
        for _, curve in self.curves:
            curve.setData([], [])

    def draw(self, series: dict[str, Series], window_s: float | None, grew: set[str] | None, follow: bool) -> None:
        """Update the visible curves whose series grew (all of them when ``grew`` is None)."""
        everything, self._stale = grew is None or self._stale, False
        for spec, curve in self.curves:
            if not curve.isVisible() or not (everything or spec.series in grew):
                continue
            s = series.get(spec.series)
            if s is None or spec.quantity not in s.values:
                continue
            rows = s.window(window_s)
            curve.setData(s.time_s[rows], s.values[spec.quantity][rows])
        self._series = series
        if follow:
            self.follow(series.get("imu"), window_s)

    def follow(self, imu: Series | None, window_s: float | None) -> None:
        """Show the newest ``window_s`` seconds (the whole session when None)."""
        if imu is None or imu.count == 0:
            return
        end = imu.time_s[imu.count - 1]
        start = imu.time_s[0] if window_s is None else end - window_s
        self.items[0].setXRange(start, max(end, start + 1e-3), padding=0)

    def _mouse_moved(self, position) -> None:
        item = next((i for i in self.items if i.sceneBoundingRect().contains(position)), None)
        if item is None:
            return
        t_s = item.getViewBox().mapSceneToView(position).x()
        for line in self.crosshair:
            line.setPos(t_s)
            line.show()
        self.readout.setText(self.read_at(t_s))

    def read_at(self, t_s: float) -> str:
        """The visible curves' values at the samples nearest ``t_s``."""
        parts = [f"t {t_s:.2f} s"]
        visible = self.visible_labels()
        for spec in self._specs:
            values = []
            for curve in spec.curves:
                s = self._series.get(curve.series)
                row = None if s is None or curve.label not in visible or curve.quantity not in s.values else s.at(t_s)
                if row is not None:
                    values.append(f"{curve.label} {s.values[curve.quantity][row]:+.2f}")
            if values:
                parts.append(f"{spec.title} ({spec.unit}): " + ", ".join(values))
        return "   |   ".join(parts)

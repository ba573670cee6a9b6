"""Stacked time plots on one shared time axis, fed from ``Series`` buffers.

Each curve is created once and updated with ``setData`` only when its series grew (or the window
changed); a view that follows the newest data hands a curve only the samples that draw each pixel column
(``series.per_pixel``: at most four a column), a paused one every sample, which pyqtgraph's peak
downsampling and clipping to the view keep cheap to zoom into. A frame does not set
the curves: the newest samples of every curve of a plot are drawn by one item (``Heads``), each
joined to its curve at the curve's last sample, so Qt repaints only the strip they cover, from the
curves' cached pixmaps (setting whole curves would repaint every plot, and each pyqtgraph
``setData`` costs more than the drawing). A curve takes its head's samples (one whole repaint) once
they span ``HEAD_S``, when the time axis steps, or when its series stops growing (``stale``). The axes move in steps, not every frame: under software rendering re-laying an
axis costs more than drawing the curves, so the time axis advances by a fraction of the window and
the value axes change only when the data leaves them or shrinks well inside them; a window longer
than the session shows it from 0. The legend above the plots has one entry per label and toggles a
curve on every plot that carries that label. A crosshair follows the mouse and reads every visible
curve at the nearest sample under it, in a small table beside the cursor over the plots (a label in
the layout would widen the plots as it grows; a band across them would hide their tops). A circular quantity (a heading, 0..360°) is not joined across its
jumps from one end of the circle to the other. A reference curve (the aircraft's own estimate) is
dashed and drawn beneath the others.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtGui, QtWidgets

from groundstation.ui.series import Series, clock_series, per_pixel, shared_gaps

PER_PIXEL = 4  # samples a pixel column beyond which a following view's curves keep only those that draw it

PEN_STYLES = {"solid": QtCore.Qt.SolidLine, "dash": QtCore.Qt.DashLine, "dot": QtCore.Qt.DotLine,
              "dashdot": QtCore.Qt.DashDotLine, "dashdotdot": QtCore.Qt.DashDotDotLine}
LEFT_AXIS_PX = 60
GAP_BRUSH = (220, 60, 60, 50)
FOLLOW_STEPS = 10  # the time axis advances by about a tenth of the window at a time
HEAD_S = 1.0  # a curve takes its head's samples when these span this: one whole repaint a second
Y_HEADROOM = 0.15  # of the data's span, above and below, when the value axis is re-fitted
Y_SHRINK = 3.0  # re-fit when the axis spans more than this many times the data
FLAT, FLAT_SHOWN = 1e-6, 0.1  # data flatter than this (of its size) is shown on an axis spanning this of its size, or 1
READOUT_GAP_PX = 16  # between the cursor and the readout beside it
LEGEND_COLUMNS = 6  # more entries (the live estimators, onboard, compass and GPS) wrap onto further legend rows


def refit(low: float, high: float, shown: tuple[float, float], span: float | None = None) -> tuple[float, float] | None:
    """A new range for an axis whose data spans ``low``..``high`` (``span``: of the data, if more),
    when the data leaves the ``shown`` range or shrinks well inside it; else None: keep it."""
    if not (math.isfinite(low) and math.isfinite(high)):
        return None
    span = max(high - low, span or 0.0)
    if span <= FLAT * max(abs(low), abs(high), 1.0):  # a flat line (a SITL's HDOP, a current of 0 A): ticks need room
        span = max(FLAT_SHOWN * max(abs(low), abs(high)), 1.0)
    if low < shown[0] or high > shown[1] or shown[1] - shown[0] > Y_SHRINK * span:
        return low - Y_HEADROOM * span, high + Y_HEADROOM * span
    return None


@dataclass(frozen=True)
class Curve:
    series: str  # which Series: "imu" or "onboard"
    quantity: str  # a key of that Series' values
    label: str  # legend entry; curves sharing it are toggled together
    color: str
    wraps_at: float | None = None  # the period of a circular quantity (360 for a heading in °)
    reference: bool = False  # dashed, beneath the others (the aircraft's own estimate under the host's)
    style: str | None = None  # a key of PEN_STYLES: another session's curves (``ui.session_list``); None: solid, dashed for a reference

    def pen(self):
        return pg.mkPen(self.color, width=1, style=PEN_STYLES[self.style or ("dash" if self.reference else "solid")])

    def connect(self, values: np.ndarray) -> dict:
        """``setData``'s ``connect``: for a circular quantity, no line across a jump of over half a turn."""
        if self.wraps_at is None:
            return {}
        joined = np.zeros(len(values), dtype=bool)
        joined[:-1] = np.abs(np.diff(values)) < self.wraps_at / 2
        return {"connect": joined}


@dataclass(frozen=True)
class Plot:
    title: str
    unit: str  # "" for a dimensionless quantity
    curves: tuple[Curve, ...]

    @property
    def axis_label(self) -> str:
        return f"{self.title} ({self.unit})" if self.unit else self.title


class Heads(pg.GraphicsObject):
    """The newest samples of the curves of one plot, as one item in its view (data coordinates)."""

    PAD_PX = 2.0  # around the samples' bounds: the one-pixel pens' width, so nothing is left behind

    def __init__(self):
        super().__init__()
        self._samples: dict[int, tuple[Curve, QtGui.QPen, np.ndarray, np.ndarray]] = {}  # by curve index
        self._bounds: dict[int, tuple[float, float, float, float]] = {}  # t0, t1, lowest and highest value
        self._rect = QtCore.QRectF()
        self._changed = False

    @property
    def pending(self) -> bool:
        return bool(self._samples)

    def has(self, index: int) -> bool:
        return index in self._samples

    def samples(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        entry = self._samples.get(index)
        return (np.empty(0), np.empty(0, dtype=np.float32)) if entry is None else entry[2:]

    def set(self, index: int, curve: Curve, pen: QtGui.QPen, t: np.ndarray, values: np.ndarray) -> None:
        """Curve ``index``'s head: copies (the series shifts its buffers in place)."""
        finite = values[np.isfinite(values)]
        self._samples[index] = (curve, pen, t.copy(), values.copy())
        low, high = (float(finite.min()), float(finite.max())) if len(finite) else (math.nan, math.nan)
        self._bounds[index] = (float(t[0]), float(t[-1]), low, high)
        self._changed = True

    def drop(self, index: int) -> None:
        if self._samples.pop(index, None) is not None:
            del self._bounds[index]
            self._changed = True

    def value_range(self) -> tuple[float, float] | None:
        finite = [b for b in self._bounds.values() if math.isfinite(b[2])]
        return (min(b[2] for b in finite), max(b[3] for b in finite)) if finite else None

    def commit(self) -> None:
        """Schedule the repaint of what changed since the last call: the old and the new bounds."""
        if not self._changed:
            return
        self._changed = False
        self.prepareGeometryChange()
        if not self._bounds:
            self._rect = QtCore.QRectF()
            return
        t0, t1 = min(b[0] for b in self._bounds.values()), max(b[1] for b in self._bounds.values())
        low, high = self.value_range() or (0.0, 0.0)
        px, py = self.pixelVectors()
        pad_x, pad_y = (0.0, 0.0) if px is None else (self.PAD_PX * px.length(), self.PAD_PX * py.length())
        self._rect = QtCore.QRectF(t0 - pad_x, low - pad_y, t1 - t0 + 2 * pad_x, high - low + 2 * pad_y)

    def boundingRect(self) -> QtCore.QRectF:
        return self._rect

    def path(self, index: int) -> QtGui.QPainterPath:
        """Curve ``index``'s head as drawn: broken at gap rows (NaN) and, circular, across a wrap."""
        curve, _, t, values = self._samples[index]
        return pg.arrayToQPath(t, values, connect=curve.connect(values).get("connect", "finite"))

    def paint(self, painter, *args) -> None:
        for index in sorted(self._samples, key=lambda i: not self._samples[i][0].reference):
            painter.setPen(self._samples[index][1])  # the references first: beneath the others, as their curves
            painter.drawPath(self.path(index))


class StackedPlots(pg.GraphicsLayoutWidget):
    """``hidden``: labels whose curves start switched off (shown greyed in the legend)."""

    userInteracted = QtCore.Signal()  # the user panned or zoomed: the caller stops following

    def __init__(self, plots: tuple[Plot, ...], hidden: frozenset[str] = frozenset(), parent=None):
        super().__init__(parent)
        self.setBackground("w")
        self.items: list[pg.PlotItem] = []
        self._stale = True  # a curve was switched on: it needs its data even if nothing grew
        self._next_column_s = -math.inf  # where the pixel column after the newest sample drawn begins (``shows_nothing_new``)
        self._series: dict[str, Series] = {}  # as last drawn, for the crosshair
        self._specs = plots
        self._gaps_drawn: set[tuple[float, float]] = set()
        self.curves: list[tuple[Curve, pg.PlotDataItem]] = []
        self.older: list[pg.PlotDataItem] = []  # each curve's binned history (``Series.older``)
        self._older_drawn: list[tuple | None] = []
        self.heads: list[Heads] = []  # each plot's curves' newest samples (see the module's doc)
        self._heads_of: list[Heads] = []  # by curve index
        # Each curve's series and time of its last sample, where its head starts (another series: none).
        self._curve_end: list[tuple[Series, float] | None] = []
        self._decimated: list[bool] = []  # each curve holds the samples that draw its pixel columns, not all
        # The legend sits above the plots, not over them: new data then never repaints it.
        labels = list(dict.fromkeys(c.label for spec in plots for c in spec.curves))
        self.legend = pg.LegendItem(colCount=max(1, min(len(labels), LEGEND_COLUMNS)), labelTextColor="#222")
        self.addItem(self.legend, row=0, col=0)
        in_legend: dict[str, pg.PlotDataItem] = {}  # the curve each legend entry drives
        for row, spec in enumerate(plots, start=1):
            item = self.addPlot(row=row, col=0)
            item.setLabel("left", spec.axis_label)
            item.getAxis("left").enableAutoSIPrefix(False)  # the label's unit stays the unit of the numbers
            item.hideAxis("bottom")  # one time axis, under the last plot
            item.getAxis("left").setWidth(LEFT_AXIS_PX)  # equal widths keep the stacked time axes aligned
            item.setDownsampling(auto=True, mode="peak")
            item.setClipToView(True)
            item.getViewBox().sigRangeChangedManually.connect(self.userInteracted)
            if self.items:
                item.setXLink(self.items[0])
            heads = Heads()
            item.addItem(heads, ignoreBounds=True)
            self.heads.append(heads)
            for spec_curve in spec.curves:
                # One-pixel pens: Qt's raster engine strokes them several times faster than wider ones.
                curve = item.plot(pen=spec_curve.pen())
                older = item.plot(pen=spec_curve.pen())
                for c in (curve, older):
                    c.setVisible(spec_curve.label not in hidden)
                    c.setZValue(-1 if spec_curve.reference else 0)
                    # Kept as a pixmap between their updates: the heads' strip repaints from it.
                    c.curve.setCacheMode(QtWidgets.QGraphicsItem.CacheMode.DeviceCoordinateCache)
                self.older.append(older)
                self._older_drawn.append(None)
                self._heads_of.append(heads)
                self._curve_end.append(None)
                self._decimated.append(False)
                if spec_curve.label not in in_legend:
                    in_legend[spec_curve.label] = curve
                    self.legend.addItem(curve, spec_curve.label)
                    sample, text = self.legend.items[-1]
                    text.mouseClickEvent = sample.mouseClickEvent  # the name toggles as its eye does
                self.curves.append((spec_curve, curve))
            self.items.append(item)
        for row, item in enumerate(self.items, start=1):
            # Equal preferred heights and stretch: the plots share the height (the time axis' plot
            # would otherwise get less, its larger size hint taken as a fixed part).
            item.setPreferredHeight(100)
            self.ci.layout.setRowStretchFactor(row, 1)
        self.items[-1].showAxis("bottom")
        # Seconds after 20 min too, not "ks"; before the label, or pyqtgraph fixes the prefix of the range now
        self.items[-1].getAxis("bottom").enableAutoSIPrefix(False)
        self.items[-1].setLabel("bottom", "time", units="s")
        self.crosshair = [pg.InfiniteLine(angle=90, movable=False, pen=pg.mkPen("#555", style=QtCore.Qt.DotLine))
                          for _ in self.items]
        for item, line in zip(self.items, self.crosshair):
            item.addItem(line, ignoreBounds=True)
            line.hide()
        self.readout = QtWidgets.QLabel(self)  # over the plots: it never takes room from them
        self.readout.setStyleSheet("background: rgba(255, 255, 255, 215); color: #222; padding: 2px 4px")
        self.readout.setAttribute(QtCore.Qt.WA_TransparentForMouseEvents)
        self.readout.setTextFormat(QtCore.Qt.RichText)
        self.readout.hide()
        self._cursor = None  # the scene position the readout was read at
        self.scene().sigMouseMoved.connect(self._mouse_moved)
        # a pan under a still cursor (the arrow keys, a live view's scroll): read the time now under it
        self.items[0].getViewBox().sigXRangeChanged.connect(self._read_again)
        for label, curve in in_legend.items():  # the legend drives the others
            curve.visibleChanged.connect(lambda c=curve, label=label: self._mirror(label, c.isVisible()))

    def _mirror(self, label: str, visible: bool) -> None:
        for i, ((spec, curve), older) in enumerate(zip(self.curves, self.older)):
            if spec.label == label:
                older.setVisible(visible)
                if not visible:
                    self._heads_of[i].drop(i)
                if curve.isVisible() != visible:
                    curve.setVisible(visible)
        for sample, text in self.legend.items:  # its eye: pyqtgraph repaints it only when clicked
            if text.text == label:
                sample.update()
        for heads in self.heads:
            heads.commit()
        self._stale = True

    @property
    def stale(self) -> bool:
        """A curve was switched on since the last draw, or holds samples in its head: it needs drawing
        even if nothing grew (a stopped series' curve then takes its head's samples)."""
        return self._stale or any(heads.pending for heads in self.heads)

    def shows_nothing_new(self, newest_s: float) -> bool:
        """Whether samples up to ``newest_s`` stay in the pixel column of the newest sample drawn (and no
        curve was switched on): drawing them now would change no column a person could tell apart from
        the next frame's, which draws them anyway."""
        return not self._stale and newest_s < self._next_column_s

    def _columns(self) -> tuple[float, float]:
        """The time axis' pixel columns: where the first begins, and their width (0 before it has a width)."""
        box = self.items[0].getViewBox()
        low, high = box.viewRange()[0]
        return low, (high - low) / box.width() if box.width() > 0 else 0.0

    def _note_column(self, end_s: float) -> None:
        low, pixel_s = self._columns()
        self._next_column_s = low + (math.floor((end_s - low) / pixel_s) + 1) * pixel_s if pixel_s > 0 else -math.inf

    def show_every_sample(self, series: dict[str, Series], window_s: float | None) -> None:
        """The curves that hold only the samples drawing their pixel columns set with every sample, the
        time range kept: a paused view is zoomed into."""
        for i, (spec, curve) in enumerate(self.curves):
            s = series.get(spec.series)
            if self._decimated[i] and s is not None and s.has(spec.quantity):
                self._set_curve(i, s, *s.data(spec.quantity, window_s), 0.0, None)
        for heads in self.heads:
            heads.commit()

    def drawn(self, curve: pg.PlotDataItem) -> tuple[np.ndarray, np.ndarray]:
        """(time, values) of the samples drawn for ``curve`` (one of ``curves``): its own and its head's."""
        i = next(i for i, (_, c) in enumerate(self.curves) if c is curve)
        if curve.xData is None:
            return np.empty(0), np.empty(0, dtype=np.float32)
        t, values = self._heads_of[i].samples(i)  # from the curve's last sample on
        return np.concatenate([curve.xData, t[1:]]), np.concatenate([curve.yData, values[1:]])

    def visible_labels(self) -> set[str]:
        return {spec.label for spec, curve in self.curves if curve.isVisible()}

    def set_visible(self, label: str, visible: bool) -> None:
        self._mirror(label, visible)

    def clear_data(self) -> None:
        for curve in [c for _, c in self.curves] + self.older:
            curve.setData([], [])
        for i, heads in enumerate(self._heads_of):
            heads.drop(i)
            heads.commit()
        self._older_drawn = [None] * len(self.older)
        self._curve_end = [None] * len(self.curves)
        self._decimated = [False] * len(self.curves)
        self._next_column_s = -math.inf
        for item in self.items:
            for region in [i for i in item.items if isinstance(i, pg.LinearRegionItem)]:
                item.removeItem(region)
        self._gaps_drawn: set[tuple[float, float]] = set()

    def _mark_gaps(self, gaps: list[tuple[float, float]]) -> None:
        """Shade the time with no samples (port gone, radio lost), once per gap."""
        for start, end in [g for g in gaps if g not in self._gaps_drawn]:
            for item in self.items:
                region = pg.LinearRegionItem((start, end), movable=False, brush=GAP_BRUSH, pen=pg.mkPen(None))
                region.setZValue(-10)
                item.addItem(region, ignoreBounds=True)
        self._gaps_drawn.update(gaps)

    def draw(self, series: dict[str, Series], window_s: float | None, grew: set[str] | None, pixels: bool = False) -> None:
        """Update the visible curves whose series grew (all of them when ``grew`` is None) and
        follow the newest ``window_s`` seconds (the whole session when None). ``pixels``: a curve with
        more than ``PER_PIXEL`` samples a pixel column keeps those that draw each column (``series.per_pixel``:
        a 10-minute window draws 2,000 samples a curve, not 60,000), as a view that follows the newest data
        shows them; else every sample (a view paused to look back and zoom in)."""
        everything, self._stale = grew is None or self._stale, False
        clock = clock_series(series)
        if clock is not None:
            self._mark_gaps(shared_gaps(series))
            everything |= self._follow_time(clock, window_s)  # the time axis moved: every plot is repainted anyway
        columns = self._columns() if pixels else None
        for i, (spec, curve) in enumerate(self.curves):
            grown = everything or spec.series in grew
            if not curve.isVisible() or not (grown or self._heads_of[i].has(i)):
                continue
            s = series.get(spec.series)
            if s is None or not s.has(spec.quantity):
                continue
            t, values = s.data(spec.quantity, window_s)
            self._set_curve(i, s, t, values, HEAD_S if grown and not everything else 0.0, columns)
            if not grown:
                continue
            t, older = s.older(spec.quantity, window_s)
            key = (len(t), t[0] if len(t) else None)
            if key != self._older_drawn[i]:  # changes only when rows are binned or the window moves past them
                self.older[i].setData(t, older, **spec.connect(older))
                self._older_drawn[i] = key
        self._series = series
        if clock is not None:
            for item, heads in zip(self.items, self.heads):
                self._fit_values(item, heads)
            self._note_column(clock.end_s)
        for heads in self.heads:
            heads.commit()

    def _set_curve(self, i: int, series: Series, t: np.ndarray, values: np.ndarray, head_s: float,
                   columns: tuple[float, float] | None) -> None:
        """Curve ``i`` shows ``t``, ``values`` of ``series``: its head the samples since its last one while
        they span at most ``head_s``, else the curve all of them (a copy: the series shifts its buffers in
        place), or those that draw its pixel ``columns`` (their first's start and their width) when there are
        more than ``PER_PIXEL`` a column."""
        spec, curve = self.curves[i]
        drawn, end_s = self._curve_end[i] or (None, None)
        if head_s > 0.0 and drawn is series and len(t) and end_s <= t[-1] <= end_s + head_s:
            joined = int(np.searchsorted(t, end_s))  # the curve's last sample: the head starts there
            self._heads_of[i].set(i, spec, curve.opts["pen"], t[joined:], values[joined:])
            return
        self._decimated[i] = columns is not None and columns[1] > 0 and len(t) > PER_PIXEL * (t[-1] - t[0]) / columns[1]
        if self._decimated[i]:
            keep = per_pixel(t, values, *columns)
            t, values = t[keep], values[keep]  # copies
        else:
            t, values = t.copy(), values.copy()
        curve.setData(t, values, **spec.connect(values))
        self._curve_end[i] = (series, float(t[-1])) if len(t) else None
        self._heads_of[i].drop(i)

    def _follow_time(self, clock: Series, window_s: float | None) -> bool:
        """Step the time axis along; a window longer than the session shows it from 0 until full.
        True when it moved."""
        first, end = clock.start_s, clock.end_s
        span = end - first if window_s is None else window_s
        step = 2.0 ** math.ceil(math.log2(max(span, 1.0) / FOLLOW_STEPS))
        right = math.ceil(end / step + 1e-9) * step
        if window_s is None:
            x_range = (first, right)
        else:
            left = max(right - window_s, min(first, 0.0))
            x_range = (left, left + window_s)
        # Compared with the range shown, not the last one set: the user may have zoomed since.
        if x_range == tuple(self.items[0].getViewBox().viewRange()[0]):
            return False
        self.items[0].setXRange(*x_range, padding=0)
        return True

    def _fit_values(self, item: pg.PlotItem, heads: Heads) -> None:
        lows, highs = [], []
        head_range = heads.value_range()
        if head_range is not None:
            lows.append(head_range[0])
            highs.append(head_range[1])
        for curve in item.listDataItems():
            bounds = curve.dataRect() if curve.isVisible() else None  # computed once per setData
            if bounds is not None and math.isfinite(bounds.top()) and math.isfinite(bounds.bottom()):
                lows.append(bounds.top())
                highs.append(bounds.bottom())
        low, high = (min(lows), max(highs)) if lows else (math.nan, math.nan)
        y_range = refit(low, high, item.getViewBox().viewRange()[1])
        if y_range is not None:
            item.setYRange(*y_range, padding=0)

    def _mouse_moved(self, position) -> None:
        item = next((i for i in self.items if i.sceneBoundingRect().contains(position)), None)
        self._cursor = QtCore.QPointF(position)
        if item is None:
            self.readout.hide()
            return
        t_s = item.getViewBox().mapSceneToView(position).x()
        for line in self.crosshair:
            line.setPos(t_s)
            line.show()
        self.readout.setText(self.read_at(t_s))
        self.readout.adjustSize()
        self.readout.move(*self._readout_place(self.mapFromScene(position)))
        self.readout.show()

    def _read_again(self) -> None:
        if self.readout.isVisible() and self._cursor is not None:
            self._mouse_moved(self._cursor)

    def _readout_place(self, cursor: QtCore.QPoint) -> tuple[int, int]:
        """Beside the cursor, on the side with room (right, else left), never over the point read; a
        box as large as its text, so the curves elsewhere stay in sight."""
        size = self.readout.size()
        x = cursor.x() + READOUT_GAP_PX
        if x + size.width() > self.width():
            x = cursor.x() - READOUT_GAP_PX - size.width()
        y = min(max(cursor.y() - size.height() // 2, 0), max(self.height() - size.height(), 0))
        return max(x, 0), y

    def leaveEvent(self, event) -> None:
        self.readout.hide()
        for line in self.crosshair:
            line.hide()
        super().leaveEvent(event)

    def read_at(self, t_s: float) -> str:
        """The visible curves' values at the samples nearest ``t_s``, a row per legend label and a
        column per plot (rich text); a curve without a value there (a gap) is left blank, not "nan"."""
        visible = self.visible_labels()
        rows: dict[str, dict[int, float]] = {}
        for column, spec in enumerate(self._specs):
            for curve in spec.curves:
                s = self._series.get(curve.series)
                value = None if s is None or curve.label not in visible else s.value_at(curve.quantity, t_s)
                if value is not None and math.isfinite(value):
                    rows.setdefault(curve.label, {})[column] = value
        header = "".join(f"<th align=right>&nbsp;{spec.axis_label}</th>" for spec in self._specs)
        body = "".join(f"<tr><td>{html.escape(label)}</td>" + "".join(
            f"<td align=right>&nbsp;{values[c]:+.2f}</td>" if c in values else "<td></td>" for c in range(len(self._specs)))
            + "</tr>" for label, values in rows.items())
        return f"<table cellspacing=0><tr><th align=left>t {t_s:.2f} s</th>{header}</tr>{body}</table>"

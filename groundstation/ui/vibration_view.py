"""The Vibration tab: the vibration view (``analysis.vibration.vibration_summary``) of the session's data
shown so far: a live session's rows, or a file's up to the replay's position (the end, once played or
sought there).

An amplitude spectrum of the chosen sensor (three axes in dB on a log-frequency axis, as PX4 Flight Review
and ArduPilot's WebTools show them; every peak marked, the strongest few labelled where their labels do
not collide on screen), its
spectrogram (the three axes' density summed) as an image (time across, frequency up on the same log axis, log
colour), a
time range (all the data, or from / to seconds of session time) and the text of the summary: peaks,
levels, clipping, motors and the notch suggestion in the autopilot's parameters. It computes when the
tab is first shown for a session and on "Compute"; a range without enough samples is said in the tab's
own banner.

The what-if (``analysis.whatif``): a notch or low-pass at a frequency (the suggested notch by default) on
the data sampled fast enough for it; "Filter" shows the chosen sensor's spectrum before and after, the
filter's gain and phase (its lag at 10-30 Hz marked), and its text (attenuation at the peak, phase lag,
the attitude difference or why there is none); a filter no data can carry is said in the banner.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from groundstation.analysis.vibration import AXES, SENSORS, UNITS, VibrationError, VibrationSummary, vibration_summary
from groundstation.session.product import SessionData, build_product
from groundstation.session.view import Session
from groundstation.ui.steady_layout import BannerOverlay

if TYPE_CHECKING:
    from groundstation.analysis.whatif import WhatIf

AXIS_COLOURS = {"x": "#d62728", "y": "#2ca02c", "z": "#1f77b4"}  # red, green, blue: the axes as a 3D view draws them
PEAK_BRUSH = "#222222"
BEFORE_PEN, AFTER_PEN = "#777777", "#d62728"  # the spectrum before the filter grey, after it red
BODE_FLOOR_DB = -60.0  # a notch's centre is -inf dB: drawn at this floor
SPECTRUM_RANGE_DB = 120.0  # a bin of zero amplitude (-inf dB) is drawn this far below the strongest bin
# The log-frequency axis labelled at 1, 2 and 5 of each decade, as Flight Review's and WebTools' read
# (pyqtgraph's own log ticks label every minor step and their texts run together above 40 Hz)
FREQUENCY_TICKS_HZ = [m * 10.0**k for k in range(-1, 5) for m in (1, 2, 5)]
DECADES_HZ = [f for f in FREQUENCY_TICKS_HZ if f == 10.0 ** round(np.log10(f))]  # the spectrogram's short axis: 1, 2, 5 crowd it
LOG_ROWS = 256  # the spectrogram's rows on its log-frequency axis
MOST_PEAK_LABELS = 5  # more labels than this crowd the plot; the text below lists every peak
FILTER_TIP = "What this filter would do: the spectrum before and after, its gain and phase, the attitude difference where the IMU carries it"
NO_FREQUENCY = "set a frequency"  # the what-if's frequency box at 0 (no notch suggested): Filter waits for one
LABEL_GAP_PX = 4.0  # the least room between two labels' boxes on screen


def frequency_ticks(frequencies_hz=FREQUENCY_TICKS_HZ) -> list:
    """``setTicks``' levels for an axis in log10(Hz): ``frequencies_hz`` labelled, no minor labels."""
    return [[(float(np.log10(f)), f"{f:g}") for f in frequencies_hz], []]


def log_rows(frequency_hz: np.ndarray, density: np.ndarray) -> tuple[np.ndarray, float, float]:
    """A spectrogram's (T, F) density on ``LOG_ROWS`` rows evenly spaced in log10(Hz) from the first bin above
    zero to the last, each row the bin its centre falls in (nothing interpolated: a low bin spans several rows);
    and log10 of the rows' lowest and highest frequency."""
    step_hz = float(frequency_hz[1] - frequency_hz[0])  # Welch's bins: 0, df, 2 df, ...
    low, high = float(np.log10(frequency_hz[1])), float(np.log10(frequency_hz[-1]))
    centres_hz = 10.0 ** (low + (np.arange(LOG_ROWS) + 0.5) * (high - low) / LOG_ROWS)
    bins = np.clip(np.rint(centres_hz / step_hz).astype(int), 1, len(frequency_hz) - 1)
    return density[:, bins].T, low, high


def amplitude_db(amplitude: np.ndarray, reference: float) -> np.ndarray:
    """``20·log10(amplitude)`` (dB re 1 of the amplitude's unit), floored at ``SPECTRUM_RANGE_DB`` below
    ``reference`` (the strongest bin shown) so a zero bin stays on the plot."""
    floor = max(reference * 10.0 ** (-SPECTRUM_RANGE_DB / 20.0), np.finfo(float).tiny)
    return 20.0 * np.log10(np.maximum(amplitude, floor))


class VibrationView(QtWidgets.QWidget):
    """``draw``, ``stale`` and ``userInteracted`` as the live view's other tabs have them."""

    userInteracted = QtCore.Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.session: Session | None = None
        self.summary: VibrationSummary | None = None
        self.stale = False
        self._due = False  # compute when next shown (a new session)
        self.whole = QtWidgets.QCheckBox("All data")
        self.whole.setChecked(True)
        self.start_box, self.end_box = (QtWidgets.QDoubleSpinBox(decimals=2, maximum=1e9, suffix=" s") for _ in range(2))
        self.whole.toggled.connect(lambda on: [b.setEnabled(not on) for b in (self.start_box, self.end_box)])
        self.whole.toggled.emit(True)
        self.sensor_box = QtWidgets.QComboBox()
        self.sensor_box.addItems(list(SENSORS))
        self.sensor_box.currentTextChanged.connect(lambda _: self._show())
        self.compute_button = QtWidgets.QPushButton("Compute")
        self.compute_button.setToolTip("The spectra of the data shown so far over the range")
        self.compute_button.clicked.connect(self.compute)
        controls = QtWidgets.QHBoxLayout()
        for widget in (self.whole, QtWidgets.QLabel("from"), self.start_box, QtWidgets.QLabel("to"), self.end_box,
                       QtWidgets.QLabel("sensor"), self.sensor_box, self.compute_button):
            controls.addWidget(widget)
        controls.addStretch(1)
        from groundstation.analysis.whatif import KINDS  # here: it loads numba, which must not delay the first paint

        self.change: WhatIf | None = None
        self.filter_box = QtWidgets.QComboBox()
        self.filter_box.addItems(list(KINDS))
        self.filter_hz, self.filter_bw = (QtWidgets.QDoubleSpinBox(decimals=1, maximum=1e5, suffix=" Hz") for _ in range(2))
        self.filter_bw.setToolTip("the notch's bandwidth between its -3 dB points (0: half its centre)")
        self.filter_hz.setSpecialValueText(NO_FREQUENCY)  # shown at 0, the minimum: no "0.0 Hz" to filter at
        self.filter_box.currentTextChanged.connect(lambda kind: self.filter_bw.setEnabled(kind == "notch"))
        self.filter_button = QtWidgets.QPushButton("Filter")
        self.filter_button.clicked.connect(self.run_what_if)
        self.filter_hz.valueChanged.connect(self._offer_filter)
        self._offer_filter(self.filter_hz.value())
        what_if_row = QtWidgets.QHBoxLayout()
        for widget in (QtWidgets.QLabel("what-if"), self.filter_box, QtWidgets.QLabel("at"), self.filter_hz,
                       QtWidgets.QLabel("bandwidth"), self.filter_bw, self.filter_button):
            what_if_row.addWidget(widget)
        what_if_row.addStretch(1)
        self.before_after_plot, self.gain_plot, self.phase_plot = (pg.PlotWidget(background="w") for _ in range(3))
        self.before_after_plot.setLogMode(y=True)
        self.before_after_plot.addLegend(offset=(-10, 10))
        self.gain_plot.setLabel("left", "gain", "dB")
        self.phase_plot.setLabel("left", "phase (negative: lag)", "°")
        self.what_if_plots = QtWidgets.QWidget()
        plots = QtWidgets.QHBoxLayout(self.what_if_plots)
        plots.setContentsMargins(0, 0, 0, 0)
        for plot in (self.before_after_plot, self.gain_plot, self.phase_plot):
            plot.setLabel("bottom", "frequency", "Hz")
            plots.addWidget(plot)
        self.what_if_plots.hide()
        self.banner = QtWidgets.QLabel()
        self.banner.setWordWrap(True)
        self.banner.setStyleSheet("background:#fde0e0; color:#8b0000; padding:4px")
        self.banner.hide()
        self.spectrum_plot = pg.PlotWidget(background="w")
        self.spectrum_plot.setLabel("bottom", "frequency", "Hz")
        self.spectrum_plot.setLogMode(x=True)  # curves are given in Hz; markers and labels sit at log10(Hz)
        self.spectrum_plot.getAxis("bottom").setTicks(frequency_ticks())
        self.spectrum_plot.getAxis("bottom").enableAutoSIPrefix(False)  # ticks in Hz: it called them kHz (log10 > 1)
        self.spectrum_plot.addLegend(offset=(-10, 10))
        self.peak_marks = pg.ScatterPlotItem(size=10, symbol="t", brush=PEAK_BRUSH, pen=None)
        self.peak_texts: list[pg.TextItem] = []  # the strongest peaks' labels, strongest first; those that collide hidden
        # a zoom or resize changes what collides: laid out again once the view's new transform is set
        self.spectrum_plot.getViewBox().sigTransformChanged.connect(self._place_labels)
        self.spectrogram_plot = pg.PlotWidget(background="w")
        self.spectrogram_plot.setLabel("bottom", "time", "s")
        self.spectrogram_plot.setLabel("left", "frequency", "Hz")
        self.spectrogram_plot.getAxis("left").setTicks(frequency_ticks(DECADES_HZ))  # log10(Hz), as the spectrum's (issue 34)
        self.spectrogram_plot.getAxis("left").enableAutoSIPrefix(False)
        self.image = pg.ImageItem(axisOrder="row-major")
        self.image.setColorMap(pg.colormap.get("viridis"))
        self.spectrogram_plot.addItem(self.image)
        self.text = QtWidgets.QPlainTextEdit(readOnly=True)
        self.text.setLineWrapMode(QtWidgets.QPlainTextEdit.WidgetWidth)
        self.text.setMaximumHeight(170)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(controls)
        layout.addLayout(what_if_row)
        layout.addWidget(self.spectrum_plot, 3)
        layout.addWidget(self.spectrogram_plot, 2)
        layout.addWidget(self.what_if_plots, 2)
        layout.addWidget(self.text)
        # over the spectrum's top, as the window's banners lie over its plots: a refusal moves nothing
        self._banner_overlay = BannerOverlay(self.spectrum_plot, (self.banner,))

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self.summary = None
        self.change = None
        for box in (self.filter_hz, self.filter_bw):  # the last file's notch is not this one's (``compute`` suggests)
            box.setValue(0.0)
        self._due = session is not None
        self._clear()

    def draw(self, series, window_s, grew) -> None:
        """Called by the live view while the tab is shown: computes once per session, then on request."""
        if self._due:
            self.compute()

    def compute(self) -> None:
        """The summary of the session's rows (a file's: all of them; live: so far) over the range; a refusal in the banner."""
        self._due = False
        if self.session is None:
            return
        data = self._snapshot()
        start, end = (None, None) if self.whole.isChecked() else (self.start_box.value(), self.end_box.value())
        self.change = None
        try:
            self.summary = vibration_summary(data, start, end)
        except VibrationError as error:
            self.summary = None
            self._clear()
            self.banner.setText(f"No vibration view: {error}")
            self.banner.show()
            return
        self.banner.hide()
        if self.whole.isChecked():
            self.start_box.setValue(self.summary.start_s)
            self.end_box.setValue(self.summary.end_s)
        if self.summary.notch:  # the what-if starts at the suggested notch
            self.filter_hz.setValue(self.summary.notch["frequency_hz"])
            self.filter_bw.setValue(self.summary.notch["bandwidth_hz"])
        self._show()

    def _snapshot(self) -> SessionData:
        """What the analysis reads: a file's whole product (``RevealSession.data``: "All data" is the whole
        file, not the part played so far); a live session's product of its tables now (the reader goes on
        adding rows)."""
        if self.session.seekable:
            return self.session.data
        view = self.session.view
        with self.session.lock:
            return build_product({}, view.catalogue, {name: table.to_dict() for name, table in view.tables.items()},
                                 view.filters, settings_at_start=view.settings())

    def run_what_if(self) -> None:
        """What the filter set in the row would do over the summary's range; a refusal in the banner."""
        from groundstation.analysis.whatif import what_if

        if self.session is None or self.summary is None:
            return
        kind, bandwidth = self.filter_box.currentText(), self.filter_bw.value() or None
        try:
            self.change = what_if(self._snapshot(), kind, self.filter_hz.value(), bandwidth if kind == "notch" else None,
                                  self.summary.start_s, self.summary.end_s)
        except VibrationError as error:
            self.change = None
            self.banner.setText(f"No what-if: {error}")
            self.banner.show()
        else:
            self.banner.hide()
        self._show()

    def _offer_filter(self, frequency_hz: float) -> None:
        """Filter only at a frequency: none is set before a notch is suggested or the user types one."""
        self.filter_button.setEnabled(frequency_hz > 0.0)
        self.filter_button.setToolTip(FILTER_TIP if frequency_hz > 0.0 else "Set a frequency to filter at (no notch is suggested)")

    def _clear(self) -> None:
        self.spectrum_plot.clear()
        self.peak_texts = []
        self.image.clear()
        self.text.clear()
        for plot in (self.before_after_plot, self.gain_plot, self.phase_plot):
            plot.clear()
        self.what_if_plots.setVisible(self.change is not None)

    def _show(self) -> None:
        """Draw the summary for the chosen sensor (the first it has when it lacks that one)."""
        if self.summary is None:
            return
        self._clear()
        spectra = self.summary.spectra
        sensor = self.sensor_box.currentText() if self.sensor_box.currentText() in spectra else next(iter(spectra))
        sp = spectra[sensor]
        self.spectrum_plot.setLabel("left", f"{sensor} amplitude", f"dB re 1 {sp.unit}")
        frequency_hz = sp.frequency_hz[1:]  # the zero-frequency bin has no place on a log axis
        reference = max(float(np.max(sp.amplitude[axis][1:])) for axis in AXES)
        db = {axis: amplitude_db(sp.amplitude[axis][1:], reference) for axis in AXES}
        for axis in AXES:
            self.spectrum_plot.plot(frequency_hz, db[axis], pen=pg.mkPen(AXIS_COLOURS[axis], width=1), name=axis)
        peaks = [p for p in self.summary.peaks if p.sensor == sensor]
        at = [(float(np.log10(p.frequency_hz)), float(np.interp(p.frequency_hz, frequency_hz, db[p.axis]))) for p in peaks]
        self.peak_marks.setData([x for x, _ in at], [y for _, y in at])
        self.spectrum_plot.addItem(self.peak_marks)
        strongest = sorted(zip(peaks, at), key=lambda pair: -pair[0].amplitude)[:MOST_PEAK_LABELS]
        for p, position in strongest:
            text = pg.TextItem(f"{p.frequency_hz:.1f} Hz {p.axis}" + (f" {p.label}" if p.label else ""), color="#222222", anchor=(0.5, 1.2))
            text.setPos(*position)
            self.spectrum_plot.addItem(text, ignoreBounds=True)  # labels never move the range they are laid out in
            self.peak_texts.append(text)
        spectrum_box = self.spectrum_plot.getViewBox()
        spectrum_box.updateAutoRange()  # the range and transform the labels are laid out in, now rather than at paint
        spectrum_box.updateMatrix()
        self._place_labels()
        t, image = sp.spectrogram_t_s, sp.spectrogram_psd
        floor = np.finfo(float).tiny
        rows, low, high = log_rows(sp.frequency_hz, image)
        self.image.setImage(np.log10(np.maximum(rows, floor)), autoLevels=True)
        step_s = (t[1] - t[0]) if len(t) > 1 else sp.nperseg / sp.rate_hz
        self.image.setRect(QtCore.QRectF(t[0] - step_s / 2, low, step_s * len(t), high - low))
        self.spectrogram_plot.setTitle(f"{sensor} spectrogram, '{sp.table}' (log density)")
        self.text.setPlainText("\n".join(self.summary.lines() + (self.change.lines() if self.change else [])))
        if self.change is not None:
            self._show_what_if(sensor)

    def _place_labels(self) -> None:
        """Show the labels strongest first, each only where its box on screen keeps ``LABEL_GAP_PX`` from
        every label already shown."""
        shown: list[QtCore.QRectF] = []
        gap = LABEL_GAP_PX / 2
        for text in self.peak_texts:
            text.setVisible(True)
            text.updateTransform(force=True)  # its box for the view as it is now, not as last painted
            box = text.sceneBoundingRect().adjusted(-gap, -gap, gap, gap)
            clear = not any(box.intersects(other) for other in shown)
            text.setVisible(clear)
            if clear:
                shown.append(box)

    def _show_what_if(self, sensor: str) -> None:
        from groundstation.analysis.whatif import LAG_AT_HZ

        change = self.change
        filtered = change.spectra.get(sensor) or next(iter(change.spectra.values()))
        self.before_after_plot.setTitle(f"{filtered.sensor}, '{filtered.table}' at {filtered.rate_hz:.0f} Hz")
        self.before_after_plot.setLabel("left", "density (x+y+z)", f"({UNITS[filtered.sensor]})²/Hz")
        floor = np.finfo(float).tiny
        for name, spectrum, pen in (("before", filtered.before, BEFORE_PEN), ("after", filtered.after, AFTER_PEN)):
            self.before_after_plot.plot(spectrum.frequency_hz[1:], np.maximum(spectrum.total_psd[1:], floor),
                                        pen=pg.mkPen(pen, width=1), name=name)
        self.gain_plot.setTitle(f"the {change.filter} at {change.bode_rate_hz:.0f} Hz")
        self.gain_plot.plot(change.bode_hz, np.maximum(change.magnitude_db, BODE_FLOOR_DB), pen=pg.mkPen(AFTER_PEN, width=1))
        self.phase_plot.plot(change.bode_hz, change.phase_deg, pen=pg.mkPen(AFTER_PEN, width=1))
        lags = change.phase_lag_deg
        self.phase_plot.setTitle("lag " + " / ".join(f"{lag:.0f}°" for lag in lags.values())
                                 + " at " + " / ".join(f"{hz:g}" for hz in lags) + " Hz")
        for hz in LAG_AT_HZ:
            if hz in lags:
                self.phase_plot.addItem(pg.InfiniteLine(hz, pen=pg.mkPen("#999999", style=QtCore.Qt.DashLine)))

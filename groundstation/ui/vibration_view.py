"""The Vibration tab: the vibration view (``analysis.vibration.vibration_summary``) of the session's data
shown so far: a live session's rows, or a file's up to the replay's position (the end, once played or
sought there).

An amplitude spectrum of the chosen sensor (three axes, the peaks marked and labelled), its
spectrogram (the three axes' density summed) as an image (time across, frequency up, log colour), a
time range (all the data, or from / to seconds of session time) and the text of the summary: peaks,
levels, clipping, motors and the notch suggestion in the autopilot's parameters. It computes when the
tab is first shown for a session and on "Compute"; a range without enough samples is said in the tab's
own banner.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pyqtgraph as pg
from PySide6 import QtCore, QtWidgets

from groundstation.analysis.vibration import AXES, SENSORS, VibrationError, VibrationSummary, vibration_summary
from groundstation.session.view import Session

AXIS_COLOURS = {"x": "#d62728", "y": "#2ca02c", "z": "#1f77b4"}  # red, green, blue: the axes as a 3D view draws them
PEAK_BRUSH = "#222222"


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
        self.banner = QtWidgets.QLabel()
        self.banner.setWordWrap(True)
        self.banner.setStyleSheet("background:#fde0e0; color:#8b0000; padding:4px")
        self.banner.hide()
        self.spectrum_plot = pg.PlotWidget(background="w")
        self.spectrum_plot.setLabel("bottom", "frequency", "Hz")
        self.spectrum_plot.addLegend(offset=(-10, 10))
        self.peak_marks = pg.ScatterPlotItem(size=10, symbol="t", brush=PEAK_BRUSH, pen=None)
        self.peak_texts: list[pg.TextItem] = []
        self.spectrogram_plot = pg.PlotWidget(background="w")
        self.spectrogram_plot.setLabel("bottom", "time", "s")
        self.spectrogram_plot.setLabel("left", "frequency", "Hz")
        self.image = pg.ImageItem(axisOrder="row-major")
        self.image.setColorMap(pg.colormap.get("viridis"))
        self.spectrogram_plot.addItem(self.image)
        self.text = QtWidgets.QPlainTextEdit(readOnly=True)
        self.text.setLineWrapMode(QtWidgets.QPlainTextEdit.WidgetWidth)
        self.text.setMaximumHeight(170)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(controls)
        layout.addWidget(self.banner)
        layout.addWidget(self.spectrum_plot, 3)
        layout.addWidget(self.spectrogram_plot, 2)
        layout.addWidget(self.text)

    def set_session(self, session: Session | None) -> None:
        self.session = session
        self.summary = None
        self._due = session is not None
        self._clear()

    def draw(self, series, window_s, grew) -> None:
        """Called by the live view while the tab is shown: computes once per session, then on request."""
        if self._due:
            self.compute()

    def compute(self) -> None:
        """The summary of the session's rows so far over the range; a refusal in the banner."""
        self._due = False
        if self.session is None:
            return
        view = self.session.view
        with self.session.lock:  # a snapshot: the reader thread goes on adding rows
            data = SimpleNamespace(tables={name: table.to_dict() for name, table in view.tables.items()}, catalogue=view.catalogue)
        start, end = (None, None) if self.whole.isChecked() else (self.start_box.value(), self.end_box.value())
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
        self._show()

    def _clear(self) -> None:
        self.spectrum_plot.clear()
        self.peak_texts = []
        self.image.clear()
        self.text.clear()

    def _show(self) -> None:
        """Draw the summary for the chosen sensor (the first it has when it lacks that one)."""
        if self.summary is None:
            return
        self._clear()
        spectra = self.summary.spectra
        sensor = self.sensor_box.currentText() if self.sensor_box.currentText() in spectra else next(iter(spectra))
        sp = spectra[sensor]
        self.spectrum_plot.setLabel("left", f"{sensor} amplitude", sp.unit)
        for axis in AXES:
            self.spectrum_plot.plot(sp.frequency_hz, sp.amplitude[axis], pen=pg.mkPen(AXIS_COLOURS[axis], width=1), name=axis)
        peaks = [p for p in self.summary.peaks if p.sensor == sensor]
        self.peak_marks.setData([p.frequency_hz for p in peaks], [float(np.interp(p.frequency_hz, sp.frequency_hz, sp.amplitude[p.axis]))
                                                                 for p in peaks])
        self.spectrum_plot.addItem(self.peak_marks)
        for p in peaks:
            text = pg.TextItem(f"{p.frequency_hz:.1f} Hz {p.axis}" + (f" {p.label}" if p.label else ""), color="#222222", anchor=(0.5, 1.2))
            text.setPos(p.frequency_hz, float(np.interp(p.frequency_hz, sp.frequency_hz, sp.amplitude[p.axis])))
            self.spectrum_plot.addItem(text)
            self.peak_texts.append(text)
        t, image = sp.spectrogram_t_s, sp.spectrogram_psd
        floor = np.finfo(float).tiny
        self.image.setImage(np.log10(np.maximum(image.T, floor)), autoLevels=True)
        step_s = (t[1] - t[0]) if len(t) > 1 else sp.nperseg / sp.rate_hz
        self.image.setRect(QtCore.QRectF(t[0] - step_s / 2, 0.0, step_s * len(t), float(sp.frequency_hz[-1])))
        self.spectrogram_plot.setTitle(f"{sensor} spectrogram, '{sp.table}' (log density)")
        self.text.setPlainText("\n".join(self.summary.lines()))

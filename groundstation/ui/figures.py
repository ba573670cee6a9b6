"""An experiment's ``report.Figure`` drawn with pyqtgraph and written as a PNG, with or without a display.

The only Qt the experiments use (``groundstation experiments`` calls ``write_png``). It needs a
``QApplication``; when none exists one is created, and on Linux with neither ``DISPLAY`` nor
``WAYLAND_DISPLAY`` nor ``QT_QPA_PLATFORM`` set, ``QT_QPA_PLATFORM`` is first set to ``offscreen``
(Qt would otherwise abort the process for want of a display). Nothing is shown on screen either way.

White background, the title and axis labels (with their units) in black, a legend, one colour per
series from a ten-colour palette (a series labelled ``truth`` is drawn black), log axes as the
figure asks (points that are not positive are left out of a log axis, which cannot show them).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from groundstation.experiments.report import Figure

WIDTH_PX, HEIGHT_PX = 1000, 600
# Matplotlib's "tab10": ten colours told apart on white and by most colour-blind readers.
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")
TRUTH_COLOR = "#000000"

_app = None  # the QApplication made here, kept alive for the process


def write_png(figure: Figure, path: str | Path) -> Path:
    """Draw ``figure`` and save it as a PNG at ``path``; OSError if the file cannot be written."""
    _ensure_application()
    import pyqtgraph as pg
    from pyqtgraph import exporters
    from PySide6 import QtCore, QtWidgets

    widget = pg.PlotWidget(background="w")
    widget.resize(WIDTH_PX, HEIGHT_PX)
    # Laid out at its size (so the title and axes get their room) without ever appearing on a screen.
    widget.setAttribute(QtCore.Qt.WidgetAttribute.WA_DontShowOnScreen)
    widget.show()
    plot = widget.getPlotItem()
    plot.setTitle(figure.title, color="k", size="13pt")
    plot.setLabel("bottom", figure.x_label, color="k")
    plot.setLabel("left", figure.y_label, color="k")
    for axis in ("bottom", "left"):
        plot.getAxis(axis).setPen("k")
        plot.getAxis(axis).setTextPen("k")
        plot.getAxis(axis).enableAutoSIPrefix(False)  # the label's unit stays the unit of the numbers
    plot.showGrid(x=True, y=True, alpha=0.2)
    plot.setLogMode(x=figure.log_x, y=figure.log_y)
    plot.addLegend(offset=(-10, 10), labelTextColor="k", brush=(255, 255, 255, 220), pen="k")
    colours = iter(PALETTE * (1 + len(figure.series) // len(PALETTE)))
    for series in figure.series:
        x, y = _drawable(series.x, series.y, figure.log_x, figure.log_y)
        colour = TRUTH_COLOR if series.label == "truth" else next(colours)
        plot.plot(x, y, name=series.label, pen=pg.mkPen(colour, width=2), antialias=True)
    QtWidgets.QApplication.processEvents()
    image = exporters.ImageExporter(plot)
    image.parameters()["width"] = WIDTH_PX
    rendered = image.export(toBytes=True)
    path = Path(path)
    if not rendered.save(str(path), "PNG"):
        raise OSError(f"could not write the PNG {path}")
    widget.close()
    widget.deleteLater()
    return path


def _drawable(x, y, log_x: bool, log_y: bool) -> tuple[np.ndarray, np.ndarray]:
    """The finite points, and only positive ones on a log axis."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    keep = np.isfinite(x) & np.isfinite(y)
    if log_x:
        keep &= x > 0
    if log_y:
        keep &= y > 0
    return x[keep], y[keep]


def _ensure_application() -> None:
    global _app
    from PySide6 import QtWidgets

    if QtWidgets.QApplication.instance() is not None:
        return
    headless = not any(os.environ.get(v) for v in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"))
    if sys.platform.startswith("linux") and headless:
        os.environ["QT_QPA_PLATFORM"] = "offscreen"
    _app = QtWidgets.QApplication(sys.argv[:1])

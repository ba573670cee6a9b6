"""The workbook's ``Vibration`` sheet: the vibration view of the exported time range
(``analysis.vibration.vibration_summary``): its text lines (source, peaks, levels, clipping, notch),
then each sensor's spectrum as a table (frequency, amplitude per axis, total density) with a chart of
the amplitudes against frequency beside it. A range too short for a spectrum gets the reason instead.
"""

from __future__ import annotations

import numpy as np
from openpyxl.cell import WriteOnlyCell
from openpyxl.chart import Reference, ScatterChart, Series
from openpyxl.styles import Font
from openpyxl.utils import get_column_letter

from groundstation.export.excel_chart import numeric_chart

from groundstation.analysis.vibration import AXES, VibrationError, vibration_summary
from groundstation.export.excel_stream import header_cell, text_cell

TITLE = "Vibration"
# The spectrum table's columns: frequency, the three axes' amplitudes, the total density. The density spans
# decades (1e-9 to 1e3 in one log): scientific, so a small one is not shown as 0.00000.
NUMBER_FORMATS = ("0.000", "0.00000", "0.00000", "0.00000", "0.000E+00")
MIN_WIDTH = 10  # characters: the sheet's text column at least


def write_vibration_sheet(workbook, data, window: tuple[float, float]) -> None:
    """The sheet for ``data`` between the session times ``window`` (the exported rows' first and last)."""
    sheet = workbook.create_sheet(TITLE)
    try:
        summary = vibration_summary(data, *window)
    except VibrationError as error:
        sheet.append([text_cell(sheet, f"no vibration view for the exported range: {error}")])
        return
    tables = {sensor: (headers(sensor, spectrum), columns(spectrum)) for sensor, spectrum in summary.spectra.items()}
    for i, width in enumerate(column_widths(list(tables.values())), start=1):  # a write-only sheet: before any row
        sheet.column_dimensions[get_column_letter(i)].width = width
    lines = summary.lines()
    for line in lines:
        sheet.append([text_cell(sheet, line)])
    written = len(lines)  # rows so far
    for sensor, spectrum in summary.spectra.items():
        unit = spectrum.unit
        sheet.append([])
        title = text_cell(sheet, f"{sensor} spectrum ('{spectrum.table}', Welch, Hann, {spectrum.nperseg} samples, 50 % overlap)")
        title.font = Font(bold=True)  # left-aligned: it runs on into the empty cells on its right (centred, its start was cut)
        sheet.append([title])
        names, values = tables[sensor]
        sheet.append([header_cell(sheet, h) for h in names])
        first = written + 4  # the first data row (1-based): after a blank row, the title and the headers
        for row in zip(*values):
            cells = [WriteOnlyCell(sheet, value=float(v)) for v in row]
            for cell, number_format in zip(cells, NUMBER_FORMATS):
                cell.number_format = number_format
            sheet.append(cells)
        last = first + len(spectrum.frequency_hz) - 1
        span_hz = (float(spectrum.frequency_hz[0]), float(spectrum.frequency_hz[-1]))
        sheet.add_chart(amplitude_chart(sheet, sensor, unit, first, last, span_hz), f"G{first - 1}")
        written = last


def headers(sensor: str, spectrum) -> list[str]:
    unit = spectrum.unit
    squared = f"({unit})²" if "/" in unit else f"{unit}²"  # (m/s²)²/Hz, not m/s²²/Hz
    return ["frequency (Hz)", *(f"{sensor} {a} amplitude ({unit})" for a in AXES), f"{sensor} density ({squared}/Hz)"]


def columns(spectrum) -> list[np.ndarray]:
    return [spectrum.frequency_hz, *(spectrum.amplitude[a] for a in AXES), spectrum.total_psd]


def shown_width(values: np.ndarray, number_format: str) -> int:
    """The characters the widest of ``values`` takes in ``number_format`` (``0.000`` fixed or ``0.000E+00``)."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if not len(values):
        return 0
    sign = int(bool((values < 0).any()))
    decimals = len(number_format.split(".")[1].split("E")[0]) if "." in number_format else 0
    if "E" in number_format:
        return sign + 1 + (decimals and decimals + 1) + 4  # d.ddd then E+dd
    return sign + len(f"{float(np.abs(values).max()):.{decimals}f}")


def column_widths(tables: list[tuple[list[str], list[np.ndarray]]]) -> list[int]:
    """Each column's width in characters: its widest header or number over every sensor's table, and one to
    spare (a number wider than its column shows as ``###``, a header is cut by the next)."""
    widths = [MIN_WIDTH] * len(NUMBER_FORMATS)
    for names, values in tables:
        for i, (name, column, number_format) in enumerate(zip(names, values, NUMBER_FORMATS)):
            widths[i] = max(widths[i], len(name) + 1, shown_width(column, number_format) + 1)
    return widths


def amplitude_chart(sheet, sensor: str, unit: str, first: int, last: int, span_hz: tuple[float, float]) -> ScatterChart:
    chart = numeric_chart(f"{sensor} amplitude spectrum", "frequency (Hz)", f"amplitude ({unit})", span_hz)
    chart.height, chart.width = 9, 22  # cm
    chart.style = 13
    x = Reference(sheet, min_col=1, min_row=first, max_row=last)
    for j, axis in enumerate(AXES, start=2):
        series = Series(Reference(sheet, min_col=j, min_row=first - 1, max_row=last), x, title_from_data=True)
        series.marker.symbol = "none"
        series.smooth = False
        chart.series.append(series)
    return chart

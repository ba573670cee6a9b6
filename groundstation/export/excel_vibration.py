"""The workbook's ``Vibration`` sheet: the vibration view of the exported time range
(``analysis.vibration.vibration_summary``): its text lines (source, peaks, levels, clipping, notch),
then each sensor's spectrum as a table (frequency, amplitude per axis, total density) with a chart of
the amplitudes against frequency beside it. A range too short for a spectrum gets the reason instead.
"""

from __future__ import annotations

from openpyxl.cell import WriteOnlyCell
from openpyxl.chart import Reference, ScatterChart, Series

from groundstation.export.excel_chart import numeric_chart

from groundstation.analysis.vibration import AXES, VibrationError, vibration_summary
from groundstation.export.excel_stream import header_cell, text_cell

TITLE = "Vibration"


def write_vibration_sheet(workbook, data, window: tuple[float, float]) -> None:
    """The sheet for ``data`` between the session times ``window`` (the exported rows' first and last)."""
    sheet = workbook.create_sheet(TITLE)
    sheet.column_dimensions["A"].width = 16
    try:
        summary = vibration_summary(data, *window)
    except VibrationError as error:
        sheet.append([text_cell(sheet, f"no vibration view for the exported range: {error}")])
        return
    lines = summary.lines()
    for line in lines:
        sheet.append([text_cell(sheet, line)])
    written = len(lines)  # rows so far
    for sensor, spectrum in summary.spectra.items():
        unit = spectrum.unit
        sheet.append([])
        sheet.append([header_cell(sheet, f"{sensor} spectrum ('{spectrum.table}', Welch, Hann, {spectrum.nperseg} samples, 50 % overlap)")])
        headers = ["frequency (Hz)", *(f"{sensor} {a} amplitude ({unit})" for a in AXES), f"{sensor} density ({unit}²/Hz)"]
        sheet.append([header_cell(sheet, h) for h in headers])
        first = written + 4  # the first data row (1-based): after a blank row, the title and the headers
        total = spectrum.total_psd
        for k, f in enumerate(spectrum.frequency_hz):
            cells = [WriteOnlyCell(sheet, value=float(v)) for v in
                     (f, *(spectrum.amplitude[a][k] for a in AXES), total[k])]
            for cell in cells:
                cell.number_format = "0.000" if cell is cells[0] else "0.00000"
            sheet.append(cells)
        last = first + len(spectrum.frequency_hz) - 1
        span_hz = (float(spectrum.frequency_hz[0]), float(spectrum.frequency_hz[-1]))
        sheet.add_chart(amplitude_chart(sheet, sensor, unit, first, last, span_hz), f"G{first - 1}")
        written = last


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

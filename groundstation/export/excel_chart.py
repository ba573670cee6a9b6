"""The workbook's ``Chart`` sheet: charts of pitch and of roll over time for every estimate.

The charts read a decimated copy of the angles (``chart_block``: at most 2,000 points per series) on
a hidden ``Chart data`` sheet, so Excel draws them at once even for hours of flight. They are scatter
charts drawn as lines: time is a number on a value axis (a line chart's category axis labels every
point, which LibreOffice crams into an unreadable row), and the axes' labels sit at the low edge of
the plot, not where the other axis crosses zero (mid-plot for angles around zero).
"""

from __future__ import annotations

from openpyxl.chart import Reference, ScatterChart, Series

from groundstation.export.excel_stream import EXCEL_MAX_ROWS, Block, write_table

DATA_TITLE = "Chart data"
CHART_ROWS = 22  # rows each chart spans at the default row height (its 11 cm)


def numeric_chart(title: str, x_title: str, y_title: str, span: tuple[float, float]) -> ScatterChart:
    """A chart of lines against a number (time, frequency), its labels at the bottom and left edges: the
    one axis layout of every chart in the workbook (a category axis would label every point)."""
    chart = ScatterChart(scatterStyle="line")
    chart.title = title
    chart.x_axis.title, chart.y_axis.title = x_title, y_title
    chart.x_axis.axPos = "b"  # openpyxl says "l" for both value axes
    chart.x_axis.scaling.min, chart.x_axis.scaling.max = span  # the data's, not the next round number
    for axis in (chart.x_axis, chart.y_axis):
        axis.delete = False  # openpyxl's default hides the axes in recent Excel
        axis.tickLblPos = "low"  # at the plot's edge whatever the values' sign
    return chart


def line_chart(data_sheet, title: str, first_column: int, series: int, points: int, span_s: tuple[float, float]) -> ScatterChart:
    chart = numeric_chart(title, "time (s)", title, span_s)
    chart.x_axis.number_format, chart.y_axis.number_format = "0", "0"
    chart.height, chart.width = 11, 30  # cm
    times = Reference(data_sheet, min_col=1, min_row=2, max_row=points + 1)
    for column in range(first_column, first_column + series):
        line = Series(Reference(data_sheet, min_col=column, min_row=1, max_row=points + 1), times, title_from_data=True)
        line.marker.symbol = "none"
        line.smooth = False
        line.graphicalProperties.line.width = 12700  # 1 pt, in EMU
        chart.series.append(line)
    return chart


def write_chart_sheets(workbook, block: Block, advance) -> None:
    """``block``: time, then every estimate's pitch, then every estimate's roll (``chart_block``)."""
    sheet = workbook.create_sheet("Chart")
    write_table(workbook, DATA_TITLE, [block], EXCEL_MAX_ROWS, advance)
    data_sheet = workbook[DATA_TITLE]
    data_sheet.sheet_state = "hidden"
    points, series = len(block[0].values), (len(block) - 1) // 2
    sheet.append([f"Pitch and roll of every estimate, {points} points (decimated for the chart; "
                  f"the full data are on the Attitude sheet). Chart data: the hidden sheet '{DATA_TITLE}'."])
    if series:
        span_s = (float(block[0].values[0]), float(block[0].values[-1]))
        sheet.add_chart(line_chart(data_sheet, "pitch (°)", 2, series, points, span_s), "A3")
        sheet.add_chart(line_chart(data_sheet, "roll (°)", 2 + series, series, points, span_s), f"A{3 + CHART_ROWS + 1}")

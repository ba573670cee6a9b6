"""The workbook's ``Chart`` sheet: line charts of pitch and of roll over time for every estimate.

The charts read a decimated copy of the angles (``chart_block``: at most 2,000 points per series) on
a hidden ``Chart data`` sheet, so Excel draws them at once even for hours of flight.
"""

from __future__ import annotations

from openpyxl.chart import LineChart, Reference

from groundstation.export.excel_stream import EXCEL_MAX_ROWS, Block, write_table

DATA_TITLE = "Chart data"
CHART_ROWS = 22  # rows each chart spans at the default row height (its 11 cm)


def line_chart(data_sheet, title: str, first_column: int, series: int, points: int) -> LineChart:
    chart = LineChart()
    chart.title = title
    chart.y_axis.title, chart.x_axis.title = title, "time (s)"
    chart.x_axis.number_format = "0"
    chart.x_axis.delete = chart.y_axis.delete = False  # openpyxl's default hides the axes in recent Excel
    chart.height, chart.width = 11, 30  # cm
    values = Reference(data_sheet, min_col=first_column, max_col=first_column + series - 1, min_row=1, max_row=points + 1)
    chart.add_data(values, titles_from_data=True)
    chart.set_categories(Reference(data_sheet, min_col=1, min_row=2, max_row=points + 1))
    for line in chart.series:
        line.smooth = False
        line.graphicalProperties.line.width = 12700  # 1 pt, in EMU
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
        sheet.add_chart(line_chart(data_sheet, "pitch (°)", 2, series, points), "A3")
        sheet.add_chart(line_chart(data_sheet, "roll (°)", 2 + series, series, points), f"A{3 + CHART_ROWS + 1}")

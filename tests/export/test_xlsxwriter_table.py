"""The XlsxWriter table writer against the openpyxl one: the same sheets, cells and formats, read back."""

import math

import numpy as np
import pytest
from openpyxl import Workbook, load_workbook

from groundstation.export.excel_stream import EXCEL_MAX_ROWS, Column, save, write_table, write_table_xlsxwriter

xlsxwriter = pytest.importorskip("xlsxwriter", reason="the XlsxWriter engine is optional")


def blocks():
    """Two side-by-side blocks of different lengths, with NaN, inf and several number formats."""
    time_s = np.arange(23) * 0.01
    pitch = np.sin(time_s * 7.0)
    pitch[[3, 4]] = np.nan
    pitch[5] = math.inf
    events = np.arange(9, dtype=np.int64)
    return [
        [Column("time (s)", time_s, "0.000", 10.0), Column("ahf pitch (°)", pitch, "0.00", 14.0)],
        [Column("event", events, "General", 8.0)],
    ]


def read_back(path):
    workbook = load_workbook(path)
    out = {}
    for sheet in workbook.worksheets:
        cells = {(c.row, c.column): (c.value, c.number_format if c.row > 1 else c.font.b) for row in sheet.iter_rows() for c in row if c.value is not None}
        # Column widths are not compared: XlsxWriter stores Excel's padded width (10 -> 10.71), openpyxl the
        # number given; Excel shows both as the width asked for.
        out[sheet.title] = (cells, sheet.freeze_panes)
    return out


@pytest.mark.parametrize("max_rows", [EXCEL_MAX_ROWS, 10, 2])
def test_same_cells_formats_and_split_as_openpyxl(tmp_path, max_rows):
    advanced = {"openpyxl": 0, "xlsxwriter": 0}
    reference = Workbook(write_only=True)
    titles = write_table(reference, "Attitude", blocks(), max_rows, lambda n: advanced.__setitem__("openpyxl", advanced["openpyxl"] + n))
    save(reference, tmp_path / "openpyxl.xlsx")
    workbook = xlsxwriter.Workbook(tmp_path / "xlsxwriter.xlsx", {"constant_memory": True})
    assert write_table_xlsxwriter(workbook, "Attitude", blocks(), max_rows, lambda n: advanced.__setitem__("xlsxwriter", advanced["xlsxwriter"] + n)) == titles
    workbook.close()
    expected, ours = read_back(tmp_path / "openpyxl.xlsx"), read_back(tmp_path / "xlsxwriter.xlsx")
    assert list(ours) == list(expected) == titles
    assert len(titles) == math.ceil(23 / (max_rows - 1))
    for title in titles:
        assert ours[title][0] == expected[title][0]  # every value, header bold, number format
        assert ours[title][1] == expected[title][1] == "B2"
    assert advanced["openpyxl"] == advanced["xlsxwriter"] == 23


def test_xlsxwriter_alone_drops_rows_past_the_sheet_silently():
    """Why the split is ours: XlsxWriter returns -1 and writes nothing past row 1,048,576."""
    workbook = xlsxwriter.Workbook("unused.xlsx", {"in_memory": True})
    sheet = workbook.add_worksheet()
    assert sheet.write_row(EXCEL_MAX_ROWS - 1, 0, [1.0]) == 0
    assert sheet.write_row(EXCEL_MAX_ROWS, 0, [1.0]) == -1


def test_a_table_one_row_past_the_limit_continues_on_a_second_sheet(tmp_path):
    """The real limit: 1,048,576 rows with the header, so one more data row goes to "Data (2)"."""
    rows = EXCEL_MAX_ROWS  # data rows: one past the 1,048,575 a sheet holds below its header
    values = np.arange(rows, dtype=float)
    workbook = xlsxwriter.Workbook(tmp_path / "big.xlsx", {"constant_memory": True})
    titles = write_table_xlsxwriter(workbook, "Data", [[Column("n", values)]], EXCEL_MAX_ROWS, lambda n: None)
    workbook.close()
    assert titles == ["Data", "Data (2)"]
    book = load_workbook(tmp_path / "big.xlsx", read_only=True)
    assert book["Data"].max_row == EXCEL_MAX_ROWS
    assert [r for r in book["Data (2)"].iter_rows(values_only=True)] == [("n",), (rows - 1.0,)]

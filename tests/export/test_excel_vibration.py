"""The workbook's Vibration sheet: the spectrum table is the vibration view's (read back with openpyxl),
the chart plots it, and the motor peak of a simulated vibrating flight is in its text."""

import numpy as np
import pytest
from openpyxl import load_workbook

from groundstation import cli
from groundstation.analysis.vibration import vibration_summary
from groundstation.export.excel import write_workbook
from groundstation.session_makers.load import load_session


@pytest.fixture(scope="module")
def shaken(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("xvib")
    assert cli.main(["simulate", "--scenario", "static", "--duration", "20", "--vibration", "22", "--out", str(tmp / "s.gsrec")]) == 0
    return load_session(tmp / "s.gsrec", exact=True), tmp


def test_the_sheet_holds_the_spectrum_of_the_exported_range_and_a_chart(shaken):
    data, tmp = shaken
    path = tmp / "s.xlsx"
    assert "Vibration" in write_workbook(data, path, t_from=5.0)
    sheet = load_workbook(path)["Vibration"]
    rows = [[c.value for c in row] for row in sheet.iter_rows()]
    text = [r[0] for r in rows if r and isinstance(r[0], str)]
    assert text[0].startswith("vibration from 5.00 s")
    assert any("motor 1×" in t and "accel" in t for t in text)
    summary = vibration_summary(data, 5.0, float(data.time_s[-1]))
    header = rows.index(["frequency (Hz)", "accel x amplitude (m/s²)", "accel y amplitude (m/s²)",
                         "accel z amplitude (m/s²)", "accel density ((m/s²)²/Hz)"])
    spectrum = summary.spectra["accel"]
    table = np.array(rows[header + 1 : header + 1 + len(spectrum.frequency_hz)], dtype=float)
    np.testing.assert_allclose(table[:, 0], spectrum.frequency_hz)
    np.testing.assert_allclose(table[:, 3], spectrum.amplitude["z"])
    np.testing.assert_allclose(table[:, 4], spectrum.total_psd)
    assert len(sheet._charts) == 2  # gyro and accel


def test_a_range_too_short_says_why_instead(shaken):
    data, tmp = shaken
    path = tmp / "short.xlsx"
    write_workbook(data, path, t_from=5.0, t_to=5.1)
    assert "too few samples" in load_workbook(path)["Vibration"]["A1"].value


def shown(value, number_format: str) -> str:
    """A number as the sheet's format shows it: ``0.000`` fixed, ``0.000E+00`` scientific (openpyxl's formats)."""
    if "E+" in number_format:
        decimals = len(number_format.split(".")[1].split("E")[0])
        mantissa, exponent = f"{value:.{decimals}E}".split("E")
        return f"{mantissa}E{exponent[0]}{int(exponent[1:]):02d}"
    decimals = len(number_format.split(".")[1]) if "." in number_format else 0
    return f"{value:.{decimals}f}"


def test_every_number_and_header_fits_its_column(shaken):
    """Issue 34: the sheet showed ``###`` (a number wider than its column) and headers cut by their neighbours.
    Widths are in characters of the default font (Calibri 11's digit): every cell's text as its format shows it
    must fit, with a character to spare."""
    data, tmp = shaken
    path = tmp / "widths.xlsx"
    write_workbook(data, path)
    sheet = load_workbook(path)["Vibration"]
    header_rows = [row[0].row for row in sheet.iter_rows() if row[0].value == "frequency (Hz)"]
    assert len(header_rows) == 2
    for row in sheet.iter_rows(min_row=header_rows[0]):
        for cell in row:
            if cell.value is None or (isinstance(cell.value, str) and cell.row not in header_rows):
                continue  # a title or a text line: it spills into the empty cells beside it
            text = shown(cell.value, cell.number_format) if isinstance(cell.value, float) else str(cell.value)
            width = sheet.column_dimensions[cell.column_letter].width
            assert width is not None and width >= len(text) + 1, (cell.coordinate, text, width)
    titles = [c for c in sheet["A"] if isinstance(c.value, str) and " spectrum (" in c.value]
    assert len(titles) == 2 and all(c.alignment.horizontal in (None, "general", "left") for c in titles)  # not cut at the left
    densities = [c.value for c in sheet["E"] if isinstance(c.value, float)]
    assert min(d for d in densities if d > 0) < 1e-4  # a small density: shown as a number, not 0.00000
    assert any(c.number_format.endswith("E+00") for c in sheet["E"] if isinstance(c.value, float))

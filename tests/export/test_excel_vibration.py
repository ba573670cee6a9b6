"""The workbook's Vibration sheet: the spectrum table is the vibration view's (read back with openpyxl),
the chart plots it, and the motor peak of a simulated vibrating flight is in its text."""

import numpy as np
import pytest
from openpyxl import load_workbook

from groundstation import cli
from groundstation.analysis.vibration import vibration_summary
from groundstation.export.excel import write_workbook
from groundstation.session.load import load_session


@pytest.fixture(scope="module")
def shaken(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("xvib")
    assert cli.main(["simulate", "--scenario", "static", "--duration", "20", "--vibration", "22", "--out", str(tmp / "s.gsrec")]) == 0
    return load_session(tmp / "s.gsrec"), tmp


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
                         "accel z amplitude (m/s²)", "accel density (m/s²²/Hz)"])
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

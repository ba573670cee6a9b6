"""The workbook as LibreOffice reads it: every sheet converted to CSV by ``soffice``, the same cells
as openpyxl reads (LibreOffice prints 15 significant digits), continuation sheets included."""

import csv
import shutil
import subprocess

import numpy as np
import pytest
from openpyxl import load_workbook

from groundstation.export.excel import write_workbook

SOFFICE = shutil.which("soffice")
# every sheet to its own CSV (the last field, -1), values not as shown (the 9th, false), UTF-8
EVERY_SHEET_CSV = "csv:Text - txt - csv (StarCalc):44,34,UTF8,1,,0,false,true,false,false,false,-1"


@pytest.mark.skipif(SOFFICE is None, reason="LibreOffice (soffice) is not installed")
def test_libreoffice_reads_the_cells_openpyxl_reads(sim_session, tmp_path):
    path = tmp_path / "hover.xlsx"
    sheets = write_workbook(sim_session, path, max_rows=700)  # the 20 s hover's ~2000 rows on three sheets
    assert "Attitude (3)" in sheets
    subprocess.run([SOFFICE, "--headless", f"-env:UserInstallation=file://{tmp_path / 'profile'}", "--convert-to",
                    EVERY_SHEET_CSV, "--outdir", str(tmp_path), str(path)], check=True, capture_output=True, timeout=180)
    book = load_workbook(path)
    for title in ("Attitude", "Attitude (2)", "Attitude (3)", "Sensors", "Link"):
        with open(tmp_path / f"hover-{title}.csv", encoding="utf-8") as file:
            office = list(csv.reader(file))
        ours = list(book[title].iter_rows(values_only=True))
        assert len(office) == len(ours), title
        assert office[0] == ["" if h is None else h for h in ours[0]], title
        for column, header in enumerate(ours[0]):
            if header is None or header == "time (UTC)":  # a date, printed as shown
                continue
            got = np.array([float(row[column]) if row[column] else np.nan for row in office[1:]])
            expected = np.array([np.nan if row[column] is None else float(row[column]) for row in ours[1:]])
            np.testing.assert_allclose(got, expected, rtol=1e-14, atol=1e-300, err_msg=f"{title}: {header}")

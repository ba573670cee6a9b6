"""The big tables' rows as ``excel_stream`` writes them (XML joined by its kernel, sheets deflated by ISA-L),
read back by openpyxl's reader and by the zip module: every value where it was, none where a value is
missing, in every stretch of rows."""

import subprocess
import sys
import textwrap
import zipfile

import numpy as np
import pytest
from openpyxl import Workbook, load_workbook

from groundstation.export import excel_stream
from groundstation.export.excel_stream import Column, save, write_table


@pytest.fixture(scope="module")
def table():
    """Columns of every kind a sheet holds, of unequal lengths, with the numbers that format longest."""
    rng = np.random.default_rng(35)
    n = 700
    floats = rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, n)
    floats[::7] = np.nan
    floats[3::11] = np.inf
    floats[5::13] = -np.inf
    floats[:4] = (-2.2250738585072014e-308, 1.7976931348623157e308, -0.0, 5e-324)  # the longest texts
    return [
        [Column("time (s)", np.arange(n) / 100.0, "0.000"), Column("x", floats, "0.00"),
         Column("count", rng.integers(-2**62, 2**62, n - 50), "0")],  # shorter: no cell past its end
        [Column("flag", rng.random(n - 300) < 0.5), Column("tiny", rng.normal(size=n) * 1e-9, "General")],
    ]  # fmt: skip


def written(table, path, monkeypatch, chunk_rows: int) -> list[int]:
    monkeypatch.setattr(excel_stream, "CHUNK_ROWS", chunk_rows)
    book, advanced = Workbook(write_only=True), []
    write_table(book, "T", table, 1_048_576, advanced.append)
    save(book, path)
    return advanced


@pytest.mark.parametrize("chunk_rows", [64, 16_384])
def test_rows_read_back_as_the_values_in_every_stretch(table, tmp_path, monkeypatch, chunk_rows):
    path = tmp_path / "t.xlsx"
    advanced = written(table, path, monkeypatch, chunk_rows)
    assert sum(advanced) == 700 and max(advanced) == min(chunk_rows, 700)
    rows = list(load_workbook(path, read_only=True)["T"].iter_rows(values_only=True))
    assert rows[0] == ("time (s)", "x", "count", None, "flag", "tiny")
    assert len(rows) == 701
    columns = [c for block in table for c in block]
    at = [0, 1, 2, 4, 5]  # the sheet's column of each: a blank one between the blocks
    for column, index in zip(columns, at):
        got = [row[index] if index < len(row) else None for row in rows[1:]]
        values = column.values
        for i, cell in enumerate(got):
            if i >= len(values) or (values.dtype.kind == "f" and not np.isfinite(values[i])):
                assert cell is None, (column.header, i, cell)
            elif values.dtype.kind == "b":
                assert cell is bool(values[i])
            else:
                assert cell == values[i], (column.header, i)
        assert all(row[3] is None for row in rows[1:] if len(row) > 3)  # the blank column between the blocks


def test_the_stretches_make_the_same_sheet(table, tmp_path, monkeypatch):
    sheets = []
    for chunk_rows in (64, 700):
        path = tmp_path / f"{chunk_rows}.xlsx"
        written(table, path, monkeypatch, chunk_rows)
        with zipfile.ZipFile(path) as archive:
            assert archive.testzip() is None  # every part's CRC, as the zip module checks it
            sheets.append(archive.read("xl/worksheets/sheet1.xml"))
    assert sheets[0] == sheets[1]


def test_writing_a_workbook_imports_no_pandas(tmp_path):
    """pyarrow imports pandas (half a CPU second) when asked to make an array from numpy or a scalar from a
    Python string: the rows are made without either."""
    script = textwrap.dedent(f"""
        import sys
        import numpy as np
        from openpyxl import Workbook
        from groundstation.export.excel_stream import Column, save, write_table
        book = Workbook(write_only=True)
        write_table(book, "T", [[Column("x", np.linspace(0, 1, 50)), Column("n", np.arange(50))]], 1_048_576, abs)
        save(book, {str(tmp_path / "t.xlsx")!r})
        print("pandas" in sys.modules)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"

"""Big column tables streamed into openpyxl write-only sheets, with a number format per column.

openpyxl's write-only sheets take rows of plain values or of styled cells. A styled cell per value
costs a new cell object and a style lookup for every value, about 1.5x the time of plain values;
``ColumnSheet`` keeps one cell per column, its style id looked up once, and only sets its value. The
XML written is the same as openpyxl writes for styled cells.

Excel holds at most 1,048,576 rows per sheet and openpyxl does not check it in write-only mode, so
``write_table`` continues on ``TITLE (2)``, ``TITLE (3)``, ... by itself.

XlsxWriter's ``constant_memory`` mode would write the same cells about 3x faster than openpyxl
write-only (bench/bench_excel.py), but the workbook's chart and Session sheet are openpyxl's; the
export stays at about 1.1x a bare openpyxl write-only write of its rows.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import itertools
import os
from collections.abc import Callable
from zipfile import ZIP_DEFLATED, ZipFile

import numpy as np
from openpyxl.cell import Cell, WriteOnlyCell
from openpyxl.styles import Alignment, Font
from openpyxl.utils import get_column_letter
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.writer.excel import ExcelWriter

from groundstation.errors import UserError

try:  # openpyxl writes its sheets through lxml when lxml is installed, and lxml reports I/O errors its own way
    from lxml.etree import SerialisationError

    XML_WRITE_ERRORS: tuple[type[Exception], ...] = (SerialisationError,)
except ImportError:
    XML_WRITE_ERRORS = ()

EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_COLUMNS = 16_384  # XFD; openpyxl writes past it (to ZZZ, then fails) a file Excel refuses to open
CHUNK_ROWS = 2048  # rows converted to Python values at a time: bounds memory and the cancel delay
SEPARATOR_WIDTH = 3  # the blank column between side-by-side blocks


@dataclasses.dataclass(frozen=True)
class Column:
    header: str  # with its unit: "ahf pitch (°)"
    values: np.ndarray  # NaN becomes an empty cell (Excel has no NaN)
    number_format: str = "General"
    width: float = 12.0


Block = list[Column]  # columns of equal length, written side by side with other blocks


class _ColumnCell(Cell):
    """The one cell of a column, reused for every row: its style is looked up once, not per value."""

    __slots__ = ("style_id", "has_style")  # shadow StyleableObject's per-access lookups

    def __init__(self, sheet, column: int, number_format: str):
        super().__init__(sheet, column=column)
        self.number_format = number_format
        self.has_style = any(self._style)
        self.style_id = sheet.parent._cell_styles.add(self._style)


def text_cell(sheet, text: str) -> Cell:
    """A cell that holds ``text`` as text: openpyxl makes any string that starts with "=" a live formula,
    and a recording's header (its source, notes) is anybody's text (=HYPERLINK(...), =cmd|...)."""
    cell = WriteOnlyCell(sheet, value=text)
    cell.data_type = "s"
    return cell


def header_cell(sheet, text: str) -> Cell:
    cell = text_cell(sheet, text)
    cell.font = Font(bold=True)
    cell.alignment = Alignment(horizontal="center")
    return cell


class ColumnSheet(WriteOnlyWorksheet):
    """A write-only sheet: a bold, frozen header row, then rows of plain values (None: empty cell)."""

    def __init__(self, workbook, title: str, columns: list[Column | None], freeze: str | None = "B2"):
        super().__init__(workbook, title)
        workbook._add_sheet(self)  # what Workbook.create_sheet does, for this subclass
        self._cells = [None if c is None else _ColumnCell(self, i, c.number_format) for i, c in enumerate(columns, 1)]
        for i, column in enumerate(columns, 1):
            self.column_dimensions[get_column_letter(i)].width = SEPARATOR_WIDTH if column is None else column.width
        self.freeze_panes = freeze
        self.append([None if c is None else header_cell(self, c.header) for c in columns])

    def _values_to_row(self, values, row_idx):
        if row_idx == 1:  # the header: styled cells, openpyxl's own path
            yield from super()._values_to_row(values, row_idx)
            return
        for cell, value in zip(self._cells, values):
            if value is not None:
                cell._value = value  # a number: data_type stays "n"
                cell.row = row_idx
                yield cell


def layout(blocks: list[Block]) -> list[Column | None]:
    """The blocks' columns left to right, None for the blank column between two blocks."""
    out: list[Column | None] = []
    for block in blocks:
        if out:
            out.append(None)
        out.extend(block)
    return out


def check_width(title: str, blocks: list[Block]) -> None:
    """UserError when the blocks side by side need more columns than a sheet holds."""
    width = len(layout(blocks))
    if width > EXCEL_MAX_COLUMNS:
        raise UserError(f"the {title} sheet would need {width:,} columns ({len(blocks)} tables side by side); Excel "
                        f"holds {EXCEL_MAX_COLUMNS:,}: export to CSV or Parquet instead")


def table_rows(blocks: list[Block]) -> int:
    return max((len(c.values) for block in blocks for c in block), default=0)


def cell_values(column: Column | None, start: int, stop: int) -> list:
    """Python numbers for rows [start, stop) of a column; None past its end and for NaN/inf."""
    if column is None:
        return itertools.repeat(None, stop - start)
    part = column.values[start:stop]
    out = part.tolist()
    if part.dtype.kind == "f":
        for i in np.flatnonzero(~np.isfinite(part)).tolist():
            out[i] = None
    return out + [None] * (stop - start - len(out))


def write_table(workbook, title: str, blocks: list[Block], max_rows: int, advance: Callable[[int], None]) -> list[str]:
    """Writes the blocks below a header row, continuing on ``TITLE (2)``, ... past ``max_rows`` rows
    per sheet (header included); calls ``advance(n)`` after every n rows. Returns the sheet titles."""
    columns = layout(blocks)
    titles = []
    for sheet_title, first, last in sheet_pages(title, table_rows(blocks), max_rows):
        titles.append(sheet_title)
        sheet = ColumnSheet(workbook, sheet_title, columns)
        for count, rows in row_chunks(columns, first, last):
            for row in rows:
                sheet.append(row)
            advance(count)
    return titles


def sheet_pages(title: str, total: int, max_rows: int):
    """``(sheet title, first row, end row)`` of each sheet a table of ``total`` rows needs, with
    ``max_rows`` rows per sheet, its header included (at least one sheet, even for no rows)."""
    if max_rows < 2:
        raise ValueError("a sheet needs room for its header and at least one row")
    per_sheet = max_rows - 1
    for page, first in enumerate(range(0, max(total, 1), per_sheet)):
        yield (title if page == 0 else f"{title} ({page + 1})"), first, min(first + per_sheet, total)


def row_chunks(columns: list[Column | None], first: int, last: int):
    """Rows [first, last) as ``(count, rows)`` of at most CHUNK_ROWS rows of plain values."""
    for start in range(first, last, CHUNK_ROWS):
        stop = min(start + CHUNK_ROWS, last)
        yield stop - start, zip(*(cell_values(c, start, stop) for c in columns))


def save(workbook, path) -> None:
    """``Workbook.save``, but the file is closed even when writing fails: openpyxl leaves that to the
    garbage collector, and an open file cannot be deleted on Windows."""
    archive = ZipFile(path, "w", ZIP_DEFLATED, allowZip64=True)
    try:
        ExcelWriter(workbook, archive).save()
    except BaseException:
        with contextlib.suppress(OSError, ValueError):  # closing writes the zip's directory: may fail again
            archive.close()
        raise


def discard(workbook) -> None:
    """Removes the sheets' temporary files after a cancel or a failure (openpyxl removes them only
    when it saves, or when the process exits: a long-running app would pile them up)."""
    for sheet in workbook._sheets:
        writer = getattr(sheet, "_writer", None)
        if writer is None or not os.path.exists(writer.out):
            continue
        # Closing writes the XML's closing tags, which fails on a full disk; the files go anyway.
        with contextlib.suppress(OSError, ValueError, *XML_WRITE_ERRORS):
            if sheet._rows is not None:
                sheet._rows.close()
            writer.close()
        sheet._rows = None  # else its generator, collected later, writes to the closed file
        writer.cleanup()


def as_os_error(error: BaseException) -> OSError | None:
    """lxml's "IO_ENOSPC"-style write failure as the OSError it stands for (None for anything else)."""
    if not isinstance(error, XML_WRITE_ERRORS) or not str(error).startswith("IO_"):
        return None
    code = getattr(errno, str(error)[3:], None)
    return OSError(code, os.strerror(code)) if code else OSError(str(error))

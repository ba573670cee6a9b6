"""Big column tables into write-only sheets, with a number format per column, at C speed.

openpyxl writes each sheet's header row, frozen panes, column widths and every other part of the
workbook (styles, the Session sheet, the chart); the data rows of the big tables never become Python
objects: ``rows_xml`` builds their ``<row>`` XML a stretch at a time (numbers as pyarrow's shortest
round-trip text, NaN/inf as no cell, the XML around them by one compiled pass), and ``save`` puts it in
each sheet's ``<sheetData>`` as it writes the zip, deflated by ISA-L. The cells are those openpyxl wrote
value by value (tests read them back with openpyxl and LibreOffice); a 1 h export's 7.3 M cells take
about a tenth of openpyxl's CPU time (bench/bench_excel.out.md).

Excel holds at most 1,048,576 rows per sheet and openpyxl does not check it in write-only mode, so
``write_table`` continues on ``TITLE (2)``, ``TITLE (3)``, ... by itself.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import io
import os
from collections.abc import Callable
from zipfile import ZIP_DEFLATED, ZipFile

import numpy as np
import pyarrow as pa
from isal import isal_zlib
from numba import njit
from openpyxl.cell import Cell, WriteOnlyCell
from openpyxl.styles import Alignment, Font
from openpyxl.utils import get_column_letter
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.writer.excel import ExcelWriter

from groundstation.errors import UserError
from groundstation.export.tabular import arrow_array
from groundstation.text import clean

try:  # openpyxl writes its sheets through lxml when lxml is installed, and lxml reports I/O errors its own way
    from lxml.etree import SerialisationError

    XML_WRITE_ERRORS: tuple[type[Exception], ...] = (SerialisationError,)
except ImportError:
    XML_WRITE_ERRORS = ()

EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_COLUMNS = 16_384  # XFD; openpyxl writes past it (to ZZZ, then fails) a file Excel refuses to open
CHUNK_ROWS = 16_384  # rows made into XML at a time: bounds memory and the cancel delay
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
    and a recording's header (its source, notes) is anybody's text (=HYPERLINK(...), =cmd|...); without
    control characters (``text.clean``), which XML refuses (a PX4 message's colours)."""
    cell = WriteOnlyCell(sheet, value=clean(text))
    cell.data_type = "s"
    return cell


def header_cell(sheet, text: str) -> Cell:
    cell = text_cell(sheet, text)
    cell.font = Font(bold=True)
    cell.alignment = Alignment(horizontal="center")
    return cell


class ColumnSheet(WriteOnlyWorksheet):
    """A write-only sheet: a bold, frozen header row written by openpyxl; then, when the workbook is
    saved (``save``), ``rows_to_write``: (columns, first row, end row, advance) stretches of the columns
    as XML (``rows_xml``)."""

    def __init__(self, workbook, title: str, columns: list[Column | None], freeze: str | None = "B2"):
        super().__init__(workbook, title)
        workbook._add_sheet(self)  # what Workbook.create_sheet does, for this subclass
        self._cells = [None if c is None else _ColumnCell(self, i, c.number_format) for i, c in enumerate(columns, 1)]
        for i, column in enumerate(columns, 1):
            self.column_dimensions[get_column_letter(i)].width = SEPARATOR_WIDTH if column is None else column.width
        self.freeze_panes = freeze
        self.append([None if c is None else header_cell(self, c.header) for c in columns])

        self.rows_to_write: list[tuple[list[Column | None], int, int, Callable[[int], None]]] = []


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


def write_table(workbook, title: str, blocks: list[Block], max_rows: int, advance: Callable[[int], None]) -> list[str]:
    """The blocks below a header row, continuing on ``TITLE (2)``, ... past ``max_rows`` rows per sheet
    (header included); ``advance(n)`` is called after every n rows as ``save`` writes them. Returns the
    sheet titles."""
    columns = layout(blocks)
    titles = []
    for sheet_title, first, last in sheet_pages(title, table_rows(blocks), max_rows):
        titles.append(sheet_title)
        ColumnSheet(workbook, sheet_title, columns).rows_to_write.append((columns, first, last, advance))
    return titles


def sheet_pages(title: str, total: int, max_rows: int):
    """``(sheet title, first row, end row)`` of each sheet a table of ``total`` rows needs, with
    ``max_rows`` rows per sheet, its header included (at least one sheet, even for no rows)."""
    if max_rows < 2:
        raise ValueError("a sheet needs room for its header and at least one row")
    per_sheet = max_rows - 1
    for page, first in enumerate(range(0, max(total, 1), per_sheet)):
        yield (title if page == 0 else f"{title} ({page + 1})"), first, min(first + per_sheet, total)


def rows_xml(sheet: ColumnSheet, columns: list[Column | None], start: int, stop: int, first: int) -> np.ndarray:
    """The ``<row>`` elements of rows [start, stop) of ``columns`` (table rows; the sheet's row of table
    row ``first`` is 2, below the header), as bytes: a cell per finite number, with its column's style,
    none for NaN, inf or past a column's end, as openpyxl writes plain values. The numbers' text is
    pyarrow's (shortest round trip); ``_joined`` puts the XML around it."""
    count = stop - start
    pieces, texts, valid = [], [], []
    for index, (column, cell) in enumerate(zip(columns, sheet._cells), 1):
        if column is None:
            continue
        part = column.values[start:stop]
        kind, shown = part.dtype.kind, part
        if kind == "b":
            shown = part.astype(np.int8)  # a boolean cell's value is 1 or 0
        missing = np.ones(count, dtype=bool)
        missing[:len(part)] = ~np.isfinite(part) if kind == "f" else False
        values = np.zeros(count, dtype=shown.dtype)
        values[:len(part)] = shown
        texts.append(arrow_array(values, missing=missing).cast(pa.string()))
        valid.append(~missing)
        attributes = (f' s="{cell.style_id}"' if cell.has_style else "") + (' t="b"' if kind == "b" else "")
        pieces += [f'<c r="{get_column_letter(index)}', f'"{attributes}><v>']
    encoded = [piece.encode() for piece in pieces]
    piece_at = np.cumsum([0, *map(len, encoded)])
    parts = [string_parts(text) for text in texts]
    text_at = np.zeros((len(texts), count + 1), dtype=np.int64)
    base = 0
    for i, (offsets, characters) in enumerate(parts):
        text_at[i] = offsets + base
        base += len(characters)
    data = np.concatenate([np.zeros(0, np.uint8), *(characters for _, characters in parts)])
    return _joined(start - first + 2, np.frombuffer(b"".join(encoded), np.uint8), piece_at, data, text_at,
                   np.array(valid, dtype=np.bool_).reshape(len(texts), count))


def string_parts(text: pa.Array) -> tuple[np.ndarray, np.ndarray]:
    """A pyarrow string array's offsets (from 0) and its characters, end to end."""
    offsets = np.frombuffer(text.buffers()[1], dtype=np.int32, count=len(text) + 1, offset=text.offset * 4)
    data = text.buffers()[2]
    characters = np.frombuffer(data, np.uint8)[offsets[0]:offsets[-1]] if data is not None else np.zeros(0, np.uint8)
    return offsets - offsets[0], characters


ROW_OPEN, ROW_MIDDLE, CELL_CLOSE, ROW_CLOSE = (np.frombuffer(s, np.uint8) for s in (b'<row r="', b'">', b"</v></c>", b"</row>"))


@njit(cache=True)
def _digits(number: int) -> int:
    digits = 1
    while number >= 10:
        number //= 10
        digits += 1
    return digits


@njit(cache=True)
def _put(out, at, source, first, end):
    for i in range(first, end):
        out[at] = source[i]
        at += 1
    return at


@njit(cache=True)
def _put_number(out, at, number, digits):
    for i in range(digits - 1, -1, -1):
        out[at + i] = 48 + number % 10
        number //= 10
    return at + digits


@njit(cache=True)
def _joined(first_number, pieces, piece_at, text, text_at, valid):
    """``<row r="N">`` + each valid cell (``pieces[2c]`` N ``pieces[2c + 1]`` text ``</v></c>``) + ``</row>``
    for N from ``first_number``: one pass to size the XML, one to write it (pyarrow's element-wise joins
    made each cell, then each row, a string of its own)."""
    columns, count = valid.shape
    size = 0
    for i in range(count):
        digits = _digits(first_number + i)
        size += len(ROW_OPEN) + digits + len(ROW_MIDDLE) + len(ROW_CLOSE)
        for c in range(columns):
            if valid[c, i]:
                size += piece_at[2 * c + 2] - piece_at[2 * c] + digits + text_at[c, i + 1] - text_at[c, i] + len(CELL_CLOSE)
    out = np.empty(size, np.uint8)
    at = 0
    for i in range(count):
        number = first_number + i
        digits = _digits(number)
        at = _put(out, at, ROW_OPEN, 0, len(ROW_OPEN))
        at = _put_number(out, at, number, digits)
        at = _put(out, at, ROW_MIDDLE, 0, len(ROW_MIDDLE))
        for c in range(columns):
            if valid[c, i]:
                at = _put(out, at, pieces, piece_at[2 * c], piece_at[2 * c + 1])
                at = _put_number(out, at, number, digits)
                at = _put(out, at, pieces, piece_at[2 * c + 1], piece_at[2 * c + 2])
                at = _put(out, at, text, text_at[c, i], text_at[c, i + 1])
                at = _put(out, at, CELL_CLOSE, 0, len(CELL_CLOSE))
        at = _put(out, at, ROW_CLOSE, 0, len(ROW_CLOSE))
    return out


def sheet_deflate():
    """A zip entry's raw deflate by ISA-L at its fastest level: 3.3x faster than zlib's fastest (level 1), where
    compressing the sheets was a third of a 1 h export's CPU, and a smaller file (bench/bench_excel.out.md)."""
    return isal_zlib.compressobj(1, isal_zlib.DEFLATED, -15)


def save(workbook, path) -> None:
    """``Workbook.save`` with each ``ColumnSheet``'s rows put into its ``<sheetData>`` (``rows_xml``);
    the file is closed even when writing fails (openpyxl leaves that to the garbage collector, and an
    open file cannot be deleted on Windows)."""
    parts = io.BytesIO()  # openpyxl's workbook: every part, the big sheets with their header row only
    ExcelWriter(workbook, ZipFile(parts, "w", ZIP_DEFLATED, allowZip64=True)).save()
    spliced = {sheet.path[1:]: sheet for sheet in workbook._sheets if isinstance(sheet, ColumnSheet)}
    # the small parts at deflate's fastest level, the big sheets by ISA-L (``sheet_deflate``)
    archive = ZipFile(path, "w", ZIP_DEFLATED, allowZip64=True, compresslevel=1)
    try:
        with ZipFile(parts) as made:
            for info in made.infolist():
                part = made.read(info)
                sheet = spliced.get(info.filename)
                if sheet is None:
                    archive.writestr(info, part)
                    continue
                end = part.rindex(b"</sheetData>")
                with archive.open(info.filename, "w", force_zip64=True) as out:
                    out._compressor = sheet_deflate()  # before any byte: zipfile's own is zlib's
                    out.write(part[:end])
                    for columns, first, last, advance in sheet.rows_to_write:
                        for start in range(first, last, CHUNK_ROWS):
                            out.write(rows_xml(sheet, columns, start, min(start + CHUNK_ROWS, last), first))
                            advance(min(start + CHUNK_ROWS, last) - start)
                    out.write(part[end:])
        archive.close()
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

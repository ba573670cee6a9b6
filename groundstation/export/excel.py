"""A session as an Excel workbook: ``Session``, ``Attitude``, ``Sensors``, ``Link``, ``Chart`` and ``Vibration``
sheets, and ``Parameters`` for an autopilot's session.

openpyxl in write-only mode: rows go to disk as they are made, so memory stays bounded whatever the
session's length. The file is written beside the destination and renamed only when complete
(``atomic_output``); a cancel or a failure leaves nothing at the destination and no temporary
file behind. Safe to call from a worker thread: it only reads ``data``.
"""

from __future__ import annotations

from collections.abc import Callable

from openpyxl import Workbook

from groundstation.export.columns import select_rows
from groundstation.export.excel_chart import write_chart_sheets
from groundstation.export.excel_columns import attitude_block, chart_block, link_blocks, sensor_blocks
from groundstation.export.excel_parameters import write_parameters_sheet
from groundstation.export.excel_session import session_rows, write_session_sheet
from groundstation.export.excel_stream import EXCEL_MAX_ROWS, as_os_error, check_width, discard, save, table_rows, write_table
from groundstation.export.excel_vibration import write_vibration_sheet
from groundstation.export.files import ExportCancelled, atomic_output
from groundstation.session.product import SessionData


def cancel_check(cancel) -> Callable[[], bool]:
    """``cancel``: None, a ``threading.Event`` or a callable returning True to cancel."""
    if cancel is None:
        return lambda: False
    return cancel.is_set if hasattr(cancel, "is_set") else cancel


def export_workbook(data: SessionData, request, writing, cancel) -> tuple[str, list[str]]:
    """``write_workbook`` as ``export.request.FORMATS`` calls it."""
    sheets = write_workbook(data, request.out, t_from=request.t_from, t_to=request.t_to, rate_hz=request.rate_hz,
                            forced=request.overrides, overwrite=request.overwrite, progress=writing, cancel=cancel)
    return f"sheets {', '.join(sheets)}", []


def write_workbook(data: SessionData, path, *, t_from: float | None = None, t_to: float | None = None,
                   rate_hz: float | None = None, forced: dict | None = None, overwrite: bool = False,
                   max_rows: int = EXCEL_MAX_ROWS, progress: Callable[[int, int], None] | None = None,
                   cancel=None) -> list[str]:
    """Writes the workbook of ``data`` to ``path``; returns its sheet titles.

    ``t_from``/``t_to``/``rate_hz``: the rows exported, as for CSV. ``forced``: the setting overrides the
    estimators ran with (``--set``), shown on the Session sheet. ``max_rows``: rows per sheet, header
    included, before a continuation sheet (Excel's limit; lowered by tests). ``progress(done, total)``
    in rows; ``cancel`` is checked every few thousand rows and raises ExportCancelled.
    UserError: the messages of ``atomic_output`` (file exists, folder missing or unwritable, disk full); a sheet
    wider than Excel's 16,384 columns.
    """
    rows = select_rows(data.time_s, t_from, t_to, rate_hz)
    window = (data.time_s[rows[0]], data.time_s[rows[-1]])
    tables = {
        "Attitude": [attitude_block(data, rows)],
        "Sensors": sensor_blocks(data, rows, window, rate_hz),
        "Link": link_blocks(data, window),
    }
    for title, blocks in tables.items():
        check_width(title, blocks)  # before any file is made
    chart = chart_block(data, rows)
    total = sum(table_rows(blocks) for blocks in tables.values()) + len(chart[0].values)
    cancelled = cancel_check(cancel)
    done = 0

    def advance(n: int) -> None:
        nonlocal done
        done += n
        if cancelled():
            raise ExportCancelled("export cancelled; nothing was written")
        if progress is not None:
            progress(done, total)

    with atomic_output(path, overwrite) as temporary:
        workbook = Workbook(write_only=True)
        try:
            write_session_sheet(workbook, session_rows(data, rows, forced))
            titles = ["Session"]
            for title, blocks in tables.items():
                titles += write_table(workbook, title, blocks, max_rows, advance)
            write_chart_sheets(workbook, chart, advance)
            write_vibration_sheet(workbook, data, window)
            parameters = write_parameters_sheet(workbook, data)
            save(workbook, temporary)
        except BaseException as error:  # a cancel, a failure, Ctrl-C: no temporary file may stay behind
            discard(workbook)
            os_error = as_os_error(error)
            if os_error is not None:  # a full disk, said as atomic_output says it
                raise os_error from error
            raise
    return titles + ["Chart", "Vibration", *parameters]

"""The workbook's ``Parameters`` sheet: an autopilot's parameters as last set (``SessionData.parameters``),
sorted by name, and beside them each change during the session with its time. Only for a session whose
aircraft has parameters (an autopilot's link or log)."""

from __future__ import annotations

from groundstation.export.excel_session import cell_number
from groundstation.export.excel_stream import header_cell, text_cell
from groundstation.session.product import SessionData

TITLE = "Parameters"
WIDTHS = {"A": 24, "B": 16, "C": 4, "D": 20, "E": 24, "F": 16, "G": 16}
HEADERS = ("parameter", "value", "", "changed at (s)", "parameter", "from", "to")


def parameter_rows(data: SessionData) -> list[list]:
    """The sheet's rows after its header: name and value, then (from column D) the changes in time order."""
    values = [[name, cell_number(value)] for name, value in sorted(data.parameters.items())]
    changes = [[e["t_s"], e["name"], cell_number(e["previous"]), cell_number(e["value"])]
               for e in data.events if e["kind"] == "parameter"]  # fmt: skip
    rows = []
    for i in range(max(len(values), len(changes))):
        left = values[i] if i < len(values) else [None, None]
        rows.append([*left, None, *(changes[i] if i < len(changes) else [])])
    return rows


def write_parameters_sheet(workbook, data: SessionData) -> list[str]:
    """The sheet's title in a list, or nothing when the session has no parameters."""
    if not data.parameters:
        return []
    sheet = workbook.create_sheet(TITLE)
    for letter, width in WIDTHS.items():
        sheet.column_dimensions[letter].width = width
    sheet.append([header_cell(sheet, h) if h else None for h in HEADERS])
    for row in parameter_rows(data):
        sheet.append([text_cell(sheet, v) if isinstance(v, str) else v for v in row])
    return [TITLE]

"""What an experiment produces: tables to print (ours beside the paper's) and figures to draw.

Plain data, no Qt: ``groundstation experiments`` prints the tables and hands the figures to
``groundstation.ui.figures`` to be written as PNG files.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass
class Table:
    title: str
    columns: list[str]  # headers with units, e.g. "pitch MAE (deg)"
    rows: list[list]  # cells: str, int or float (floats printed with ``digits`` decimals)
    notes: list[str] = dataclasses.field(default_factory=list)  # what agrees with the paper, what not, why
    digits: int = 3

    def format(self) -> str:
        cells = [[_cell(c, self.digits) for c in row] for row in self.rows]
        widths = [max(len(h), *(len(r[i]) for r in cells)) if cells else len(h) for i, h in enumerate(self.columns)]
        lines = [self.title, "  ".join(h.ljust(w) for h, w in zip(self.columns, widths))]
        lines.append("  ".join("-" * w for w in widths))
        lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths)) for row in cells]
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def markdown(self) -> list[str]:
        """The table as markdown lines: a heading, the table, its notes as a list."""
        lines = [f"### {self.title}", "", _markdown_row(self.columns), _markdown_row(["---"] * len(self.columns))]
        lines += [_markdown_row([_cell(c, self.digits) for c in row]) for row in self.rows]
        return lines + [""] + [f"- {note}" for note in self.notes] + ([""] if self.notes else [])


@dataclasses.dataclass
class Series:
    label: str
    x: np.ndarray
    y: np.ndarray


@dataclasses.dataclass
class Figure:
    filename: str  # e.g. "seed000_slide_pitch.png", written into the --out folder
    title: str
    x_label: str  # with units
    y_label: str
    series: list[Series]
    log_x: bool = False
    log_y: bool = False


@dataclasses.dataclass
class Result:
    tables: list[Table] = dataclasses.field(default_factory=list)
    figures: list[Figure] = dataclasses.field(default_factory=list)


def _cell(value, digits: int) -> str:
    if isinstance(value, float):
        return "n/a" if not np.isfinite(value) else f"{value:.{digits}f}"
    return str(value)


def _markdown_row(cells) -> str:
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"

"""The flight report's figures as inline SVG: line plots drawn here, so the page needs no plotting
library, no script and no file beside it, and stays sharp at any zoom.

Long series are reduced to at most two points (the lowest and the highest) per pixel column, so a
spike of one sample in a million-row log still shows at full height.
"""

from __future__ import annotations

import html
import math

import numpy as np

from groundstation.text import clean

WIDTH, HEIGHT = 760, 240  # the figure without its legend, which is laid out in rows below it
MARGIN = {"left": 58, "right": 12, "top": 26, "bottom": 34}
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")  # series naming none
FONT_PX = 11
# A legend entry's text is given this many pixels per character: more than DejaVu Sans' widest capitals at 11 px
# (a browser's sans-serif), so entries never run into each other; the swatch and the space after each entry.
CHAR_PX = 0.72 * FONT_PX
SWATCH_PX, ENTRY_GAP_PX, LEGEND_ROW_PX = 14, 18, 15


def escaped(text) -> str:
    """Any text as HTML (or SVG) text: without control characters (``text.clean``), then escaped."""
    return html.escape(clean(str(text)))


def nice_ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """Round tick values covering [lo, hi]: steps of 1, 2 or 5 times a power of ten."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        return [lo] if math.isfinite(lo) else []
    raw = (hi - lo) / count
    power = 10 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    first = math.ceil(lo / step) * step
    return [first + i * step for i in range(int((hi - first) / step + 1e-9) + 1)]


def log_ticks(lo: float, hi: float, most: int = 8) -> list[float]:
    """Ticks of a log axis spanning 10**lo .. 10**hi, as their logarithms: 1, 2 and 5 times the powers
    of ten inside it, or the powers alone where those are too many."""
    powers = range(math.floor(lo), math.ceil(hi) + 1)
    for multiples in ((1, 2, 5), (1,)):
        ticks = [math.log10(m) + p for p in powers for m in multiples if lo <= math.log10(m) + p <= hi]
        if len(ticks) <= most:
            return ticks
    return ticks


def reduced(x: np.ndarray, y: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """At most the lowest and the highest point of each of ``columns`` equal spans of ``x``, in x order
    (finite points only)."""
    keep = np.isfinite(x) & np.isfinite(y)
    x, y = x[keep], y[keep]
    if len(x) <= 2 * columns:
        return x, y
    bins = np.minimum(((x - x[0]) / max(x[-1] - x[0], 1e-12) * columns).astype(int), columns - 1)
    starts = np.flatnonzero(np.r_[True, np.diff(bins) != 0])
    pick = set()
    for start, end in zip(starts, np.r_[starts[1:], len(y)]):
        segment = y[start:end]
        pick.add(start + int(np.argmin(segment)))
        pick.add(start + int(np.argmax(segment)))
    index = np.array(sorted(pick))
    return x[index], y[index]


def legend_rows(labels: list[str], width: float) -> list[list[tuple[int, float]]]:
    """Legend entries (index, x from the row's start) in rows no wider than ``width``, in order."""
    rows, x = [[]], 0.0
    for i, label in enumerate(labels):
        size = SWATCH_PX + len(label) * CHAR_PX
        if rows[-1] and x + size > width:
            rows.append([])
            x = 0.0
        rows[-1].append((i, x))
        x += size + ENTRY_GAP_PX
    return rows if rows[0] else []


def line_plot(series: list[tuple], title: str, x_label: str, y_label: str,
              log_y: bool = False, marks: list[tuple[float, str]] = ()) -> str:
    """An SVG line plot of ``series`` (label, x, y[, colour[, dashed]]: a series without a colour takes the next of
    ``COLOURS``; an estimator's is the app's, ``groundstation.palette``), a legend below it in rows that fit, and
    vertical ``marks`` (x, label) such as reboots; a plot with no finite point says so instead of drawing empty axes."""
    plot_w = WIDTH - MARGIN["left"] - MARGIN["right"]
    plot_h = HEIGHT - MARGIN["top"] - MARGIN["bottom"]
    drawn = []
    for i, (label, x, y, *style) in enumerate(series):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if log_y:
            y = np.where(y > 0, y, np.nan)
        x, y = reduced(x, y, plot_w)
        colour = style[0] if style and style[0] else COLOURS[i % len(COLOURS)]
        if len(x):
            drawn.append((label, x, np.log10(y) if log_y else y, colour, len(style) > 1 and style[1]))
    rows = legend_rows([d[0] for d in drawn], WIDTH - MARGIN["left"] - MARGIN["right"])
    height = HEIGHT + len(rows) * LEGEND_ROW_PX + (6 if rows else 0)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" '
           f'role="img" aria-label="{escaped(title)}" font-family="sans-serif" font-size="{FONT_PX}">',
           f'<text x="{WIDTH / 2}" y="15" text-anchor="middle" font-size="13" font-weight="bold">{escaped(title)}</text>']
    if not drawn:
        out.append(f'<text x="{WIDTH / 2}" y="{HEIGHT / 2}" text-anchor="middle" fill="#777">nothing to plot</text></svg>')
        return "\n".join(out)
    x_lo = min(float(x.min()) for _, x, _, _, _ in drawn)
    x_hi = max(float(x.max()) for _, x, _, _, _ in drawn)
    y_lo = min(float(y.min()) for _, _, y, _, _ in drawn)
    y_hi = max(float(y.max()) for _, _, y, _, _ in drawn)
    if x_hi <= x_lo:
        x_hi = x_lo + 1.0
    if y_hi <= y_lo:
        y_lo, y_hi = y_lo - 1.0, y_hi + 1.0
    pad = 0.05 * (y_hi - y_lo)
    y_lo, y_hi = y_lo - pad, y_hi + pad

    def px(x):
        return MARGIN["left"] + (np.asarray(x) - x_lo) / (x_hi - x_lo) * plot_w

    def py(y):
        return MARGIN["top"] + (y_hi - np.asarray(y)) / (y_hi - y_lo) * plot_h

    left, top, bottom = MARGIN["left"], MARGIN["top"], MARGIN["top"] + plot_h
    out.append(f'<rect class="area" x="{left}" y="{top}" width="{plot_w}" height="{plot_h}" fill="#fff" stroke="#999"/>')
    for tick in nice_ticks(x_lo, x_hi):
        out.append(f'<line x1="{px(tick):.1f}" x2="{px(tick):.1f}" y1="{top}" y2="{bottom}" stroke="#eee"/>'
                   f'<text x="{px(tick):.1f}" y="{bottom + 14}" text-anchor="middle">{tick:g}</text>')
    y_ticks = log_ticks(y_lo, y_hi) if log_y else nice_ticks(y_lo, y_hi)
    for tick in y_ticks:
        text = f"{10 ** tick:.3g}" if log_y else f"{tick:g}"
        out.append(f'<line x1="{left}" x2="{left + plot_w}" y1="{py(tick):.1f}" y2="{py(tick):.1f}" stroke="#eee"/>'
                   f'<text x="{left - 4}" y="{py(tick) + 4:.1f}" text-anchor="end">{text}</text>')
    row_ends: list[float] = []  # the right end of the last mark label on each row of labels, top down
    for x, label in sorted(marks):
        if x_lo <= x <= x_hi:
            # the first row where the label clears the one before it (a reboot and a clock jump 0.4 s apart
            # were written over each other)
            start = float(px(x)) + 3
            row = next((r for r, end in enumerate(row_ends) if start >= end + CHAR_PX), len(row_ends))
            row_ends[row:row + 1] = [start + CHAR_PX * len(label)]
            out.append(f'<line x1="{px(x):.1f}" x2="{px(x):.1f}" y1="{top}" y2="{bottom}" stroke="#000" stroke-dasharray="4 3"/>'
                       f'<text x="{start:.1f}" y="{top + 11 + row * LEGEND_ROW_PX}">{escaped(label)}</text>')
    for label, x, y, colour, dashed in sorted(drawn, key=lambda d: not d[4]):  # the dashed references beneath
        points = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px(x), py(y)))
        dash = ' stroke-dasharray="5 3"' if dashed else ""
        out.append(f'<polyline data-series="{escaped(label)}" fill="none" stroke="{colour}" stroke-width="1.2"{dash} points="{points}"/>')
    for r, row in enumerate(rows):
        ly = HEIGHT + 4 + r * LEGEND_ROW_PX + FONT_PX
        for i, lx in row:
            label, _, _, colour, dashed = drawn[i]
            dash = ' stroke-dasharray="3 2"' if dashed else ""
            out.append(f'<g class="legend-entry"><line x1="{left + lx:.1f}" x2="{left + lx + 10:.1f}" y1="{ly - 4}" y2="{ly - 4}" '
                       f'stroke="{colour}" stroke-width="3"{dash}/>'
                       f'<text x="{left + lx + SWATCH_PX:.1f}" y="{ly}">{escaped(label)}</text></g>')
    out.append(f'<text x="{left + plot_w / 2}" y="{HEIGHT - 4}" text-anchor="middle">{escaped(x_label)}</text>')  # under the ticks
    out.append(f'<text x="12" y="{top + plot_h / 2}" text-anchor="middle" transform="rotate(-90 12 {top + plot_h / 2})">'
               f'{escaped(y_label)}</text>')
    out.append("</svg>")
    return "\n".join(out)

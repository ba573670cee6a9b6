"""The autopilot's flight modes on the plots: a shaded band per mode span, labelled with the mode's name
on the top plot (paler while disarmed), and the mode and arming now as a line for the status bar.

The spans come from ``autopilot.modes.mode_spans`` over the view's events (the same function the flight
report uses); a session that never reports a mode (the project's own aircraft, a dataset) draws none.

A label is laid out again whenever the time axis moves (``_fit_labels``): it shows whole where its span has room
for it on screen, else the mode's name alone, else nothing (the band's tooltip names it), so short modes' labels
never run into each other (issue 34); zoomed in, they come back. It hangs on a line of its own, at its span's
start or the view's left edge, whichever is later (a span begun before the view was labelled off its left edge).
"""

from __future__ import annotations

import zlib

import pyqtgraph as pg

from groundstation.autopilot.modes import ModeSpan, mode_spans

# Pale fills that leave every curve of the palette readable above them; a mode keeps its colour
# across sessions (by a checksum of its name: Python's ``hash`` of a str changes from run to run).
FILLS = ((68, 119, 170), (34, 136, 51), (204, 187, 68), (238, 102, 119), (170, 51, 119), (102, 204, 238), (187, 187, 187))
ARMED_ALPHA, DISARMED_ALPHA = 46, 18
LABEL_PAD_PX = 6  # between a label and the next span's start


def fill(span: ModeSpan) -> pg.QtGui.QBrush:
    r, g, b = FILLS[zlib.crc32(span.mode.encode()) % len(FILLS)]
    return pg.mkBrush(r, g, b, ARMED_ALPHA if span.armed else DISARMED_ALPHA)


def label(span: ModeSpan) -> str:
    return span.mode + ("" if span.armed is None else " (armed)" if span.armed else " (disarmed)")


class ModeBands:
    """Keeps each plot widget's bands matching the spans; ``show`` is cheap when nothing changed (the
    last span only grows with a live session: its bands are stretched, not redrawn)."""

    def __init__(self):
        self._drawn: dict[int, tuple[object, list[ModeSpan], list[list[pg.LinearRegionItem]]]] = {}
        self._labels: dict[int, list[pg.InfLineLabel]] = {}  # each plot widget's, a span's each (``_fit_labels``)
        self._watched: set[int] = set()  # the plot widgets whose time axis calls ``_fit_labels``
        self._events_seen = -1
        self.spans: list[ModeSpan] = []

    def update_spans(self, events: list[dict], end_s: float | None) -> list[ModeSpan]:
        """The spans of ``events`` up to ``end_s`` (recomputed only when events came or the end moved)."""
        if end_s is None:
            self.spans, self._events_seen = [], -1
        elif len(events) != self._events_seen or (self.spans and self.spans[-1].end_s != end_s):
            self._events_seen = len(events)
            self.spans = mode_spans(events, end_s)
        return self.spans

    def show(self, plots) -> None:
        """Draw the current spans on ``plots`` (a ``StackedPlots``: one band per span on each of its plots)."""
        drawn = self._drawn.get(id(plots))
        regions = drawn[2] if drawn is not None and drawn[0] is plots else []
        attached = all(r.scene() is not None for bands in regions for r in bands)  # ``clear_data`` removes them
        old = drawn[1] if drawn is not None and drawn[0] is plots and attached else None
        if old == self.spans:
            return
        if old is not None and len(old) == len(self.spans) and old[:-1] == self.spans[:-1] and \
                (old[-1].mode, old[-1].armed, old[-1].start_s) == (self.spans[-1].mode, self.spans[-1].armed, self.spans[-1].start_s):
            for region in regions[-1]:
                region.setRegion((self.spans[-1].start_s, self.spans[-1].end_s))
        else:
            for bands in regions:
                for item, region in zip(plots.items, bands):
                    item.removeItem(region)
            made = [self._bands(plots, span) for span in self.spans]
            regions = [bands for bands, _ in made]
            self._labels[id(plots)] = [text for _, text in made]
            if id(plots) not in self._watched:
                self._watched.add(id(plots))
                plots.items[0].getViewBox().sigXRangeChanged.connect(lambda *_, p=plots: self._fit_labels(p))
        self._drawn[id(plots)] = (plots, list(self.spans), regions)
        self._fit_labels(plots)

    def _fit_labels(self, plots) -> None:
        """Each label whole, shortened to its mode, or hidden: what its span's room on screen allows."""
        labels = self._labels.get(id(plots), [])
        if not labels:
            return
        spans = self._drawn[id(plots)][1]  # as drawn: the last one stretched since its label was made
        view = plots.items[0].getViewBox()
        (low, high), width_px = view.viewRange()[0], view.width()
        if width_px <= 0 or high <= low:
            return
        px_per_s = width_px / (high - low)
        metrics = pg.QtGui.QFontMetricsF(labels[0].textItem.font())
        for span, text in zip(spans, labels):
            text.line.setValue(max(span.start_s, low))
            room = (min(span.end_s, high) - max(span.start_s, low)) * px_per_s - LABEL_PAD_PX
            fits = [t for t in (label(span), span.mode) if metrics.horizontalAdvance(t) + 2 * LABEL_PAD_PX <= room]
            text.setFormat(fits[0] if fits else "")  # its format: what the label says again when its line moves
            text.setVisible(bool(fits))

    @staticmethod
    def _bands(plots, span: ModeSpan) -> tuple[list[pg.LinearRegionItem], pg.InfLineLabel]:
        out, text = [], None
        for row, item in enumerate(plots.items):
            region = pg.LinearRegionItem((span.start_s, span.end_s), movable=False, brush=fill(span), pen=pg.mkPen(None))
            region.setZValue(-20)  # beneath the curves and the gaps' shading
            region.setToolTip(label(span))
            if row == 0:  # on an unseen line of the band's (gone with it, as its edges) that ``_fit_labels`` keeps in view
                anchor = pg.InfiniteLine(span.start_s, angle=90, movable=False, pen=pg.mkPen(None))
                anchor.setParentItem(region)
                text = pg.InfLineLabel(anchor, text=label(span), position=0.98, anchors=[(0, 0), (0, 0)], color="#333")
            item.addItem(region, ignoreBounds=True)
            out.append(region)
        return out, text

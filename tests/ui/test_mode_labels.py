"""Mode band labels (issue 34): short modes' labels ran into each other. A label shows where its span has room
for it on screen (else the mode alone, else none: the band's tooltip still names it), and never overlaps
another; zoomed in, the labels come back."""

import pytest
from PySide6 import QtCore

from groundstation.autopilot.modes import ModeSpan
from groundstation.ui.live_view import attitude_plots
from groundstation.ui.mode_bands import ModeBands
from groundstation.ui.plots import StackedPlots

SPANS = [ModeSpan(0.0, 0.4, "STABILIZE", True), ModeSpan(0.4, 0.9, "ALT_HOLD", True), ModeSpan(0.9, 1.2, "LOITER", True),
         ModeSpan(1.2, 40.0, "AUTO", True), ModeSpan(40.0, 41.0, "RTL", True), ModeSpan(41.0, 60.0, "LAND", False)]


@pytest.fixture
def shown(qtbot):
    plots = StackedPlots(attitude_plots(("ahf2",)))
    qtbot.addWidget(plots)
    plots.resize(800, 400)
    plots.show()
    qtbot.waitExposed(plots)
    bands = ModeBands()
    bands.spans = list(SPANS)
    bands.show(plots)
    return plots, bands


def visible_labels(plots, qtbot):
    qtbot.wait(50)  # the range change relays the labels out
    plots.grab()
    top = plots.items[0]
    from pyqtgraph.graphicsItems.InfiniteLine import InfLineLabel

    labels = [i for i in top.scene().items() if isinstance(i, InfLineLabel) and i.isVisible() and i.toPlainText()]
    return [(i.toPlainText(), i.mapRectToScene(i.boundingRect())) for i in labels]


def start_px(plots, t_s):
    return plots.items[0].getViewBox().mapViewToScene(QtCore.QPointF(t_s, 0)).x()


def test_labels_never_overlap_and_fit_their_spans(shown, qtbot):
    plots, _ = shown
    plots.items[0].setXRange(0.0, 60.0, padding=0)
    labels = visible_labels(plots, qtbot)
    assert labels  # the long spans keep theirs
    for i, (text, rect) in enumerate(labels):
        for other, rect2 in labels[:i]:
            assert not rect.intersects(rect2), (text, other)
        span = next(s for s in SPANS if text.startswith(s.mode))
        assert rect.right() <= start_px(plots, span.end_s) + 1, text  # inside its span
    assert {"AUTO (armed)", "LAND (disarmed)"} <= {t for t, _ in labels}
    plots.items[0].setXRange(0.0, 1.3, padding=0)  # zoomed in on the short ones: room for them
    zoomed = {t.split(" ")[0] for t, _ in visible_labels(plots, qtbot)}
    assert {"STABILIZE", "ALT_HOLD", "LOITER"} <= zoomed


def test_a_span_begun_left_of_the_view_is_labelled_inside_it(shown, qtbot):
    """A PX4 log's one mode began before the whole-flight view's left edge: its label read "ABILIZED (armed)"."""
    plots, _ = shown
    plots.items[0].setXRange(10.0, 60.0, padding=0)  # AUTO began at 1.2 s
    labels = dict(visible_labels(plots, qtbot))
    assert labels["AUTO (armed)"].left() >= start_px(plots, 10.0) - 1

"""An autopilot's parameters, texts and modes in the real window (issue 23): the Parameters tab filters as
text is typed, the modes are shaded labelled bands on the plots' time axis and the status bar says the
mode and arming; the autopilot's texts are in Events."""

from pathlib import Path

import pyqtgraph as pg
import pytest
from pymavlink import DFReader
from PySide6 import QtCore

from groundstation.autopilot.modes import mode_spans
from tests.ui.helpers import open_file, play_to_the_end

COPTER = Path(__file__).resolve().parents[2] / ".." / "shared" / "datasets" / "flightlogs" / "arducopter_cubeorange_2023-07-06_10-12-18.bin"


@pytest.fixture(scope="module")
def copter(module_window, module_qtbot):
    """The log opened and played to the end once for the module: each test reads another part of the window
    (the Parameters tab's filter, typed in by one test, is read by no other)."""
    if not COPTER.is_file():
        pytest.skip(f"{COPTER} is absent (the shared flight logs)")
    window, qtbot = module_window, module_qtbot
    open_file(window, qtbot, COPTER, timeout_ms=120000)
    assert window.loading is None and not window.banner.isVisible(), window.banner.text()
    play_to_the_end(window, qtbot)
    qtbot.wait(600)  # a figures tick
    return window


def test_the_parameters_tab_filters_as_text_is_typed(copter, qtbot):
    reader = DFReader.DFReader_binary(str(COPTER), zero_time_base=False)
    while reader.recv_match(type="PARM") is not None:
        pass
    view = copter.parameters_view
    assert sorted(view.visible_names()) == sorted(reader.params)  # DFReader's own table of PARM
    view.filter_box.setFocus()
    qtbot.keyClicks(view.filter_box, "ins_gyr")
    expected = sorted(name for name in reader.params if "INS_GYR" in name)
    assert expected and view.visible_names() == expected
    assert view.count_label.text() == f"{len(expected)} of {len(reader.params)} parameters"
    for _ in range(4):
        qtbot.keyClick(view.filter_box, QtCore.Qt.Key_Backspace)
    assert view.visible_names() == sorted(name for name in reader.params if "INS" in name)


def test_modes_are_bands_on_the_plots_and_the_mode_is_in_the_status_bar(copter):
    spans = mode_spans(copter.session.data.events, float(copter.session.data.time_s[-1]))
    assert [(s.mode, s.armed) for s in spans] == [("LOITER", True), ("RTL", True), ("RTL", False)]
    for item in copter.live_view.attitude.items:
        bands = [i for i in item.items if isinstance(i, pg.LinearRegionItem) and i.zValue() == -20]
        assert [b.getRegion() for b in bands] == [pytest.approx((s.start_s, s.end_s)) for s in spans]
    top = [i for i in copter.live_view.attitude.items[0].items if isinstance(i, pg.LinearRegionItem) and i.zValue() == -20]
    labels = [c.toPlainText() for b in top for c in b.lines[0].childItems() if isinstance(c, pg.InfLineLabel)]
    # each whole, or its mode alone where its span has no room on screen for more (issue 34: labels ran together)
    assert labels[:2] == ["LOITER (armed)", "RTL (armed)"] and labels[2] in ("RTL (disarmed)", "RTL")
    assert copter.vehicle_badge.text() == "disarmed · RTL" and copter.vehicle_badge.isVisible()


def test_the_autopilots_texts_are_in_events(copter):
    console = copter.event_console.table
    details = [console.item(row, 2).text() for row in range(console.rowCount())]
    assert any("message ArduCopter V4.3.6 (0c5e999c)" in d for d in details)
    assert any("mode RTL" in d for d in details)

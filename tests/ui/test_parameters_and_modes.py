"""An autopilot's parameters, texts and modes in the real window (issue 23): the Parameters tab filters as
text is typed, the modes are shaded labelled bands on the plots' time axis and the status bar says the
mode and arming; the autopilot's texts are in Events."""

from pathlib import Path

import json
import math

import pyqtgraph as pg
import pytest
from mavio_params import definitions
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


def test_the_parameters_tab_says_what_each_parameter_means_filters_and_marks_the_non_default_ones(copter, qtbot):
    """Issue 34: description, units, range, the value's meaning and the default, as Mission Planner shows them; the
    non-default ones alone at a click (Flight Review's list); the filter (issue 23) finds words of the descriptions
    too."""
    reader, defaults = DFReader.DFReader_binary(str(COPTER), zero_time_base=False), {}
    while (msg := reader.recv_match(type="PARM")) is not None:
        if not math.isnan(msg.Default):
            defaults[msg.Name] = msg.Default
    documented = definitions("ardupilot.copter")
    view = copter.parameters_view
    table = view.table
    headers = [table.horizontalHeaderItem(c).text() for c in range(table.columnCount())]
    assert headers == ["parameter", "value", "default", "units", "range", "meaning", "description"]
    rows = {table.item(r, 0).text(): [table.item(r, c).text() for c in range(table.columnCount())] for r in range(table.rowCount())}
    gyro = rows["INS_GYRO_FILTER"]
    assert gyro[3:5] == ["Hz", "0 .. 256"] and gyro[6] == documented["INS_GYRO_FILTER"]["description"]
    assert gyro[2] == f"{defaults['INS_GYRO_FILTER']:.0f}"
    assert rows["FRAME_CLASS"][5] == documented["FRAME_CLASS"]["values"][int(reader.params["FRAME_CLASS"])] == "Quad"
    name_row = next(r for r in range(table.rowCount()) if table.item(r, 0).text() == "INS_GYRO_FILTER")
    assert documented["INS_GYRO_FILTER"]["display_name"] in table.item(name_row, 0).toolTip()
    assert "Copter" in view.source_label.text()
    assert sorted(view.visible_names()) == sorted(reader.params)  # DFReader's own table of PARM

    def found(part: str) -> list[str]:  # the filter finds a part of a name or of a description, any case
        return sorted(n for n in reader.params if part.upper() in n or part.lower() in documented.get(n, {}).get("description", "").lower())

    view.filter_box.setFocus()
    qtbot.keyClicks(view.filter_box, "ins_gyr")
    expected = found("ins_gyr")
    assert expected and view.visible_names() == expected
    assert view.count_label.text() == f"{len(expected)} of {len(reader.params)} parameters"
    for _ in range(4):
        qtbot.keyClick(view.filter_box, QtCore.Qt.Key_Backspace)
    assert view.visible_names() == found("ins")
    view.filter_box.clear()
    qtbot.keyClicks(view.filter_box, "cutoff frequency for gyro")
    expected = found("cutoff frequency for gyro")
    assert expected and not any("CUTOFF" in n for n in expected) and view.visible_names() == expected
    view.filter_box.clear()
    assert view.non_default_box.isEnabled()
    view.non_default_box.click()  # (the tab is not on screen: a click's own signal)
    changed = sorted(n for n, value in reader.params.items() if n in defaults and value != defaults[n])
    assert len(changed) > 100 and view.visible_names() == changed
    assert view.count_label.text() == f"{len(changed)} of {len(reader.params)} parameters"
    assert table.item(name_row, 1).font().bold() == ("INS_GYRO_FILTER" in changed)
    view.window_button.click()  # the same table, in a window as wide as the flyer makes it
    detached = view.detached
    qtbot.waitUntil(detached.isVisible, timeout=10000)
    assert detached.isWindow() and detached.width() > view.width()
    assert sorted(detached.visible_names()) == sorted(reader.params) and detached.source_label.text() == view.source_label.text()


def test_modes_are_bands_on_the_plots_and_the_mode_is_in_the_status_bar(copter):
    spans = mode_spans(copter.session.data.events, float(copter.session.data.time_s[-1]))
    assert [(s.mode, s.armed) for s in spans] == [("LOITER", True), ("RTL", True), ("RTL", False)]
    for item in copter.live_view.attitude.items:
        bands = [i for i in item.items if isinstance(i, pg.LinearRegionItem) and i.zValue() == -20]
        assert [b.getRegion() for b in bands] == [pytest.approx((s.start_s, s.end_s)) for s in spans]
    top = [i for i in copter.live_view.attitude.items[0].items if isinstance(i, pg.LinearRegionItem) and i.zValue() == -20]
    labels = [c.toPlainText() for b in top for line in b.childItems() if isinstance(line, pg.InfiniteLine)
              for c in line.childItems() if isinstance(c, pg.InfLineLabel)]  # each on a line of its band's
    # each whole, or its mode alone where its span has no room on screen for more (issue 34: labels ran together)
    assert labels[:2] == ["LOITER (armed)", "RTL (armed)"] and labels[2] in ("RTL (disarmed)", "RTL")
    assert copter.vehicle_badge.text() == "disarmed · RTL" and copter.vehicle_badge.isVisible()


def test_the_autopilots_texts_are_in_events(copter):
    console = copter.event_console.table
    details = [console.item(row, 2).text() for row in range(console.rowCount())]
    assert any("message ArduCopter V4.3.6 (0c5e999c)" in d for d in details)
    assert any("mode RTL" in d for d in details)


def test_a_px4_logs_parameters_tab_says_where_descriptions_come_from_and_reads_parameters_json_beside_it(qtbot, tmp_path):
    """PX4 publishes no package of its parameter metadata: the tab says where to put its parameters.json, reads
    it from beside the log when there, says so when it is not one; the log's own defaults mark the non-default
    ones in any case (pyulog's: PX4 logs the default of each parameter not at it)."""
    from pyulog import ULog

    from groundstation.autopilot.parameter_docs import PX4_DOCS_HINT, PX4_FILE
    from groundstation.session.playback import RevealSession
    from groundstation.session_makers.load import load_session
    from groundstation.ui.parameters_view import ParametersView

    hop = COPTER.parent / "px4_fmuv5_quad_hop.ulg"
    if not hop.is_file():
        pytest.skip(f"{hop} is absent (the shared flight logs)")
    (tmp_path / hop.name).symlink_to(hop)
    session = RevealSession(load_session(tmp_path / hop.name, filters=("ahf2",)), tmp_path / hop.name, paused=True)
    view = ParametersView()
    qtbot.addWidget(view)
    view.set_session(session)
    assert view.source_label.text() == PX4_DOCS_HINT and view.non_default_box.isEnabled()
    view.non_default_box.click()
    assert view.visible_names() == sorted(ULog(str(hop)).get_default_parameters(0))
    (tmp_path / PX4_FILE).write_text(json.dumps({"parameters": [{"name": "MC_ROLLRATE_P", "shortDesc": "Roll rate P gain"}]}))
    view.set_session(session)
    assert str(tmp_path / PX4_FILE) in view.source_label.text()
    (tmp_path / PX4_FILE).write_text("[")
    view.set_session(session)
    assert view.source_label.text().startswith(f"{tmp_path / PX4_FILE}: not PX4's parameter metadata") and PX4_DOCS_HINT in view.source_label.text()

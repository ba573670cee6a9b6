"""The right-hand column and the small labels a new user reads (issue 24, defects 11 and 12): nothing
cut off in a replay, Apply moves no field, events wrap, the words the window uses are the words its
fields show; the real window, offscreen."""

import numpy as np
from PySide6 import QtWidgets

from firmware_protocol import SPEC
from groundstation.estimation import ESTIMATORS

from tests.ui.helpers import open_file, play_to_the_end
from tests.waiting import LIMIT_MS


def side_labels(window) -> list[QtWidgets.QLabel]:
    side = window.splitter.widget(1).widget()  # the scroll area's panels
    return [label for label in side.findChildren(QtWidgets.QLabel)
            if label.isVisibleTo(side) and not label.wordWrap() and label.text()]


def test_no_readout_of_the_side_column_is_cut_in_a_replay(window, qtbot, recording):
    open_file(window, qtbot, recording)
    play_to_the_end(window, qtbot)
    for _ in range(12):  # every panel's refresh, with the replay's last figures
        window.tick()
    cut = [(label.text(), label.width(), label.sizeHint().width()) for label in side_labels(window)
           if label.width() < label.sizeHint().width()]
    assert not cut
    assert window.attitude_panel.readouts["yaw"].text() != "—"


def field_positions(panel) -> list:
    return [box.mapTo(panel.window(), box.rect().topLeft()) for box in panel.boxes.values()]


def settled(panel, qtbot) -> list:
    """The fields' positions once they stay put for a second (a few redraws of every panel)."""
    positions = None
    for _ in range(20):
        qtbot.wait(1000)
        now = field_positions(panel)
        if now == positions:
            return now
        positions = now
    raise AssertionError("the fields never settled")


def test_apply_moves_no_field_and_names_the_setting_as_its_field_does(window, qtbot):
    window.start_demo()
    window.controls.setCurrentWidget(window.estimator_panel)
    panel = window.estimator_panel
    qtbot.waitUntil(lambda: panel.fields.isEnabled() and len(window.session.view.imu) > 20, timeout=LIMIT_MS)
    before = settled(panel, qtbot)  # the banners of a starting session come and go above the panels
    name, setting = next((n, s) for (n, s) in panel.boxes if n == "ahf" and s != "lam_min")  # AHF λ max
    box = panel.boxes[name, setting]
    box.setValue(box.value() * 0.5)
    panel.apply()
    assert settled(panel, qtbot) == before  # the next click lands where the user aims
    shown_as = panel._layout.labelForField(box).text()  # "AHF λ max"
    assert panel.message.text() == f"applied: {shown_as} = {box.value():g}"
    assert setting not in panel.message.text()  # not the setting's code name (lam_max)


def test_events_wrap_their_details(window, qtbot):
    window.start_demo()
    console = window.event_console
    qtbot.waitUntil(lambda: console.table.rowCount() > 2, timeout=LIMIT_MS)
    window.controls.setCurrentWidget(console)  # shown after the rows came: its columns change width
    table = console.table
    row = max(range(table.rowCount()), key=lambda r: len(table.item(r, 2).text()))
    assert table.wordWrap()
    width = table.columnWidth(2)
    needed = table.fontMetrics().horizontalAdvance(table.item(row, 2).text())
    lines = -(-needed // max(width, 1))
    assert lines > 1
    qtbot.waitUntil(lambda: table.rowHeight(row) >= lines * table.fontMetrics().lineSpacing(), timeout=LIMIT_MS)  # all of it


def test_the_small_labels_of_a_live_session(window, qtbot, tmp_path):
    window.bar.select("/dev/pts/0", 0)  # a port used before
    window.start_demo()
    view, uplink = window.live_view, window.uplink_panel
    qtbot.waitUntil(lambda: window.session.view.config is not None, timeout=LIMIT_MS)
    mode = SPEC.enum_name(SPEC.frame("CONFIG").field("mode"), window.session.view.config["mode"])
    assert mode != uplink.mode_box.itemText(0)  # the demo's firmware is in "both", the box's first is "raw"
    qtbot.waitUntil(lambda: uplink.mode_box.currentText() == mode, timeout=LIMIT_MS)  # the firmware's, at the next refresh
    colours = [spec.color.lower() for spec, _ in view.heading.curves]
    labels = [spec.label for spec, _ in view.heading.curves]
    compass = colours[labels.index("compass")]
    assert colours.count(compass) == 1  # not AHF2's black
    channels = {f"{t.name}.{c.name}": c.header for t, c in window.session.view.catalogue.channels()}
    for channel, header in channels.items():
        if channel.startswith("imu.") and channel.endswith("_rad_s"):
            assert header.endswith("(rad/s)"), header
    assert channels["imu.ahf2_bias_x_rad_s"] == "ahf2 bias x (rad/s)"
    assert ESTIMATORS["ahf2"].name == "ahf2"


def test_the_source_box_names_the_file_that_plays(window, qtbot, recording):
    window.bar.select("/dev/pts/0", 0)  # the port used last time
    open_file(window, qtbot, recording)
    assert window.bar.source == str(recording)
    assert window.bar.disconnect_button.text() == "Close file" and window.bar.disconnect_button.isEnabled()
    window.bar.disconnect_button.click()
    assert window.session is None and window.bar.disconnect_button.text() == "Disconnect"
    assert np.isfinite(window.last_file[1])


def test_help_about_says_the_version_and_links_the_docs(window, qtbot):
    from groundstation import __version__

    action = next(a for menu in window.menuBar().findChildren(QtWidgets.QMenu) for a in menu.actions()
                  if a.text().replace("&", "").startswith("About"))
    action.trigger()
    box = next(w for w in QtWidgets.QApplication.topLevelWidgets() if isinstance(w, QtWidgets.QMessageBox) and w.isVisible())
    assert f"groundstation {__version__}" in box.text() and 'href="file://' in box.text() and "README.md" in box.text()
    box.close()


def test_after_a_restart_the_source_box_shows_what_streams(qtbot, tmp_path):
    """Issue 34: the box showed the remembered port while the app streamed the simulated bridge, so
    simulated curves passed for the aircraft."""
    from PySide6 import QtCore

    from groundstation.session_makers.factory import Sessions
    from groundstation.ui.main_window import MainWindow

    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    settings.setValue("port", "/dev/ttyUSB7")
    settings.setValue("recent_sources", ["/dev/ttyUSB7"])
    window = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(window)
    window.show()
    assert window.bar.source == "/dev/ttyUSB7"  # nothing streams yet: the last source is offered
    window.start_demo("no port given: streaming from the simulated bridge")
    assert window.session is not None and window.bar.source == window.sessions.demo_spec

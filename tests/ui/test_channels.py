"""Plot any channel: every column of every table is listed; channels added to panes are drawn with
the table's numbers; the panes are remembered."""

import json

import numpy as np
from PySide6 import QtWidgets

from groundstation.session_makers.factory import Sessions

from groundstation.ui.main_window import MainWindow
from tests.waiting import LIMIT_MS


def listed(view) -> set[str]:
    tree = view.channels.tree
    return {tree.topLevelItem(i).child(j).data(0, 0x0100) for i in range(tree.topLevelItemCount())
            for j in range(tree.topLevelItem(i).childCount())}


def shown_texts(view) -> dict[str, str]:
    tree = view.channels.tree
    return {item.data(0, 0x0100): item.text(0) for i in range(tree.topLevelItemCount())
            for item in (tree.topLevelItem(i).child(j) for j in range(tree.topLevelItem(i).childCount()))}


def test_channels_are_listed_plotted_in_panes_and_remembered(window, qtbot, tmp_path):
    window.start_demo()
    view = window.live_view
    pipeline = window.session.view
    tables = {"imu": pipeline.imu, "onboard": pipeline.onboard, **pipeline.tables}
    assert listed(view) == {f"{n}.{c}" for n, t in tables.items() for c in t.columns if c != "time_s"}
    shown = shown_texts(view)  # a person's label and unit, from the session's catalogue (the spec's units)
    assert shown["imu.gyr_x_rad_s"] == "gyro x (rad/s)" and shown["baro.pressure_Pa"] == "pressure (Pa)"
    assert shown["baro.temperature_degC"] == "temperature (°C)" and shown["onboard.lambda"] == "onboard λ"
    view.tabs.setCurrentWidget(view.channels)
    view.channels.add("imu.gyr_x_rad_s")
    view.channels.new_pane()
    view.channels.add("baro.pressure_Pa")
    view.channels.add("onboard.lambda")
    assert len(view.channels.items) == 2
    curves = {spec.label: curve for spec, curve in view.channels.stacked.curves}
    qtbot.waitUntil(lambda: all(c.xData is not None and len(c.xData) > 10 for c in curves.values()), timeout=LIMIT_MS)
    for label, curve in curves.items():
        table, column = label.split(".")
        times, values = tables[table].column("time_s"), tables[table].column(column)
        row = np.flatnonzero(times == curve.xData[-1])[0]
        assert curve.yData[-1] == np.float32(values[row])
    window.close()
    again = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(again)
    assert again.live_view.channels.panes == [["imu.gyr_x_rad_s"], ["baro.pressure_Pa", "onboard.lambda"]]
    again.live_view.channels.remove_pane()  # the selected one: the first
    assert again.live_view.channels.panes == [["baro.pressure_Pa", "onboard.lambda"]]


def visible(view) -> set[str]:
    tree = view.channels.tree
    return {item.data(0, 0x0100) for i in range(tree.topLevelItemCount()) if not tree.topLevelItem(i).isHidden()
            for item in (tree.topLevelItem(i).child(j) for j in range(tree.topLevelItem(i).childCount())) if not item.isHidden()}


def test_the_search_box_filters_the_channels_as_one_types(window, qtbot):
    window.start_demo()
    view = window.live_view
    texts = shown_texts(view)
    qtbot.keyClicks(view.channels.search, "Press")
    assert visible(view) == {c for c, text in texts.items() if "press" in f"{c} {text}".lower()} != set()
    view.channels.search.clear()
    qtbot.keyClicks(view.channels.search, "gyr x")  # every word, anywhere
    assert visible(view) == {c for c, text in texts.items() if "gyr" in f"{c} {text}".lower() and "x" in f"{c} {text}".lower()}
    assert "imu.gyr_x_rad_s" in visible(view) and "imu.gyr_y_rad_s" not in visible(view)
    view.channels.search.clear()
    assert visible(view) == set(texts)


def drop_on(plots, data, item):
    """Drag ``data`` over the pane ``item`` and drop it there, as Qt delivers a drag from the channel list."""
    from PySide6 import QtCore, QtGui, QtWidgets

    point = plots.mapFromScene(item.sceneBoundingRect().center())
    enter = QtGui.QDragEnterEvent(point, QtCore.Qt.CopyAction, data, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
    QtWidgets.QApplication.sendEvent(plots.viewport(), enter)
    move = QtGui.QDragMoveEvent(point, QtCore.Qt.CopyAction, data, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
    QtWidgets.QApplication.sendEvent(plots.viewport(), move)
    drop = QtGui.QDropEvent(QtCore.QPointF(point), QtCore.Qt.CopyAction, data, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier)
    QtWidgets.QApplication.sendEvent(plots.viewport(), drop)
    return enter.isAccepted(), drop.isAccepted()


def tree_item(view, channel):
    tree = view.channels.tree
    return next(item for i in range(tree.topLevelItemCount()) for item in
                (tree.topLevelItem(i).child(j) for j in range(tree.topLevelItem(i).childCount()))
                if item.data(0, 0x0100) == channel)


def test_a_channel_dragged_from_the_list_onto_a_pane_is_plotted_there(window, qtbot):
    window.start_demo()
    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)
    channels = view.channels
    channels.add("imu.gyr_x_rad_s")
    channels.new_pane()
    qtbot.wait(100)
    data = channels.tree.mimeData([tree_item(view, "baro.pressure_Pa"), tree_item(view, "onboard.lambda")])
    assert drop_on(channels.stacked, data, channels.stacked.items[1]) == (True, True)
    assert channels.panes == [["imu.gyr_x_rad_s"], ["baro.pressure_Pa", "onboard.lambda"]]
    data = channels.tree.mimeData([tree_item(view, "imu.acc_z_g")])
    drop_on(channels.stacked, data, channels.stacked.items[0])
    assert channels.panes == [["imu.gyr_x_rad_s", "imu.acc_z_g"], ["baro.pressure_Pa", "onboard.lambda"]]
    from PySide6 import QtCore
    other = QtCore.QMimeData()
    other.setText("imu.gyr_y_rad_s")  # plain text from elsewhere is not a channel drag
    assert drop_on(channels.stacked, other, channels.stacked.items[0]) == (False, False)
    assert channels.panes == [["imu.gyr_x_rad_s", "imu.acc_z_g"], ["baro.pressure_Pa", "onboard.lambda"]]


def test_an_xy_plot_draws_east_against_north(window, qtbot):
    window.start_demo()
    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)
    view.window_box.setCurrentText("10 s")  # the session outlives the window: the XY plot shows the window's
    view.channels.add_xy("position.pos_e_m", "position.pos_n_m")
    view.channels.add_xy("gps.lon_deg", "position.pos_n_m")  # another table's: its row at or before each time
    curve, across = view.channels.xy_plots.curves
    table = window.session.view.tables["position"]
    qtbot.waitUntil(lambda: len(table) > 1300 and curve.xData is not None and across.xData is not None, timeout=LIMIT_MS)
    assert len(curve.xData) < 1100
    table = window.session.view.tables["position"]
    east, north = table.column("pos_e_m"), table.column("pos_n_m")
    rows = np.flatnonzero(np.float32(east) == np.float32(curve.xData[-1]))
    assert len(rows) and np.float32(north[rows[-1]]) == np.float32(curve.yData[-1])
    gps = window.session.view.tables["gps"]
    assert len(across.xData) == len(across.yData) > 0
    assert np.isin(np.float32(across.xData[np.isfinite(across.xData)]), np.float32(gps.column("lon_deg"))).all()
    assert view.channels.xy_plots.isVisible()


def roll_deg(q):
    """Roll of w-first quaternions by scipy (an oracle independent of the window's conversion)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_euler("ZYX", degrees=True)[:, 2]


def test_a_custom_series_from_an_expression_is_listed_plotted_and_checked(window, qtbot):
    window.start_demo()
    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)
    dialog = view.channels.new_custom()
    for text, says in (("ahf2_roll_deg +* 2", "not an expression"), ("nosuch_deg - 1", "unknown channel 'nosuch_deg'"),
                       ("__import__('os').getcwd()", "unknown function")):
        dialog.name.setText("roll_difference_deg")
        dialog.expression.setText(text)
        dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.Ok).click()
        assert dialog.isVisible() and says in dialog.message.text()
    dialog.expression.setText("ahf2_roll_deg - onboard_roll_deg")
    dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.Ok).click()
    assert not dialog.isVisible()
    assert "custom.roll_difference_deg" in listed(view)
    view.channels.add("custom.roll_difference_deg")
    (spec, curve), = view.channels.stacked.curves
    qtbot.waitUntil(lambda: curve.xData is not None and len(curve.xData) > 50, timeout=LIMIT_MS)
    # one snapshot of each table (whole rows): the demo's writer thread appends between two column reads
    imu, onboard = (table.to_dict() for table in (window.session.view.imu, window.session.view.onboard))
    times = imu["time_s"]
    t = curve.xData[-40:]
    rows = np.searchsorted(times, t)
    assert np.array_equal(times[rows], t)
    ahf2 = roll_deg(np.column_stack([imu[f"ahf2_q{c}"] for c in "wxyz"])[rows])
    before = np.searchsorted(onboard["time_s"], t, side="right") - 1  # the onboard row at or before
    aboard = roll_deg(np.column_stack([onboard[f"q{c}"] for c in "wxyz"])[before])
    assert np.allclose(curve.yData[-40:], ahf2 - aboard, atol=1e-3)
    assert json.loads(view.channels.layout_json())["custom"] == {"roll_difference_deg": "ahf2_roll_deg - onboard_roll_deg"}


def test_named_layouts_are_saved_and_chosen_from_the_menu(window, qtbot, tmp_path):
    channels = window.live_view.channels
    channels.add("imu.gyr_x_rad_s")
    channels.add_xy("position.pos_e_m", "position.pos_n_m")
    channels.save_layout("flight check")
    channels.new_pane()
    channels.add("baro.pressure_Pa")
    channels.save_layout("baro")
    window.close()
    again = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(again)
    menu = again.live_view.channels.layouts_menu
    menu.aboutToShow.emit()
    actions = {a.text(): a for a in menu.actions() if a.text()}
    assert set(actions) == {"Save layout as…", "baro", "flight check"}
    actions["flight check"].trigger()
    assert again.live_view.channels.panes == [["imu.gyr_x_rad_s"]]
    assert again.live_view.channels.xy == [["position.pos_e_m", "position.pos_n_m"]]
    actions["baro"].trigger()
    assert again.live_view.channels.panes == [["imu.gyr_x_rad_s"], ["baro.pressure_Pa"]]

"""Plot any channel: every column of every table is listed; channels added to panes are drawn with
the table's numbers; the panes are remembered."""

import numpy as np

from groundstation.session.factory import Sessions

from groundstation.ui.main_window import MainWindow


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
    qtbot.waitUntil(lambda: all(c.xData is not None and len(c.xData) > 10 for c in curves.values()), timeout=8000)
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

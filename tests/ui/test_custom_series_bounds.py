"""Custom series hold whatever is typed: the dialog refuses what cannot be plotted and says why; a
remembered layout with such an expression opens with that series off and said; a series past its time
budget at a redraw is switched off and said, and the rest of the window (and the reader) goes on."""

import json

import numpy as np
from PySide6 import QtCore, QtWidgets

from groundstation.session_makers.factory import Sessions
from groundstation.ui.channels import PREFIX
from groundstation.ui.main_window import MainWindow
from tests.ui.test_channels import listed, roll_deg


def click_ok(dialog) -> None:
    dialog.findChild(QtWidgets.QDialogButtonBox).button(QtWidgets.QDialogButtonBox.Ok).click()


def curve_of(channels, label):
    return next(curve for spec, curve in channels.stacked.curves if spec.label == label)


def test_the_dialog_refuses_what_cannot_be_plotted_and_says_why(window, qtbot):
    window.start_demo()
    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)
    imu = window.session.view.imu
    qtbot.waitUntil(lambda: len(imu) > 100, timeout=30000)  # rows to try the expressions on
    dialog = view.channels.new_custom()
    dialog.name.setText("tried")
    for text, says in (("ahf2_roll_deg + 10**10**10", "10 ** 10 ** 10 is inf in float64"),
                       ("ahf2_roll_deg + 1/0", "1 / 0 is inf in float64"),
                       ("ahf2_roll_deg + 10**400", "10 ** 400 is inf in float64"),
                       ("0**-1 * ahf2_roll_deg", "0 ** (-1) is inf in float64"),
                       ("log(abs(ahf2_roll_deg), imu.gyr_x_rad_s) + imu.gyr_x_rad_s", "log() takes 1 value, not 2"),
                       ("log(abs(ahf2_roll_deg) - 1000)", "no finite value"),
                       ("+".join(["ahf2_roll_deg"] * 300), "at most")):
        dialog.expression.setText(text)
        click_ok(dialog)
        assert dialog.isVisible() and says in dialog.message.text(), (text, dialog.message.text())
    gyr_before = imu.column("gyr_x_rad_s")[:100].copy()
    dialog.expression.setText("log(abs(ahf2_roll_deg)) + imu.gyr_x_rad_s")
    click_ok(dialog)
    assert not dialog.isVisible() and "custom.tried" in listed(view)
    view.channels.add("custom.tried")
    curve = curve_of(view.channels, "custom.tried")
    qtbot.waitUntil(lambda: curve.xData is not None and len(curve.xData) > 50, timeout=20000)
    assert np.array_equal(imu.column("gyr_x_rad_s")[:100], gyr_before)  # no value of a channel written over
    times = imu.column("time_s")
    rows = np.searchsorted(times, curve.xData[-40:])
    ahf2 = roll_deg(np.column_stack([imu.column(f"ahf2_q{c}") for c in "wxyz"])[rows])
    assert np.allclose(curve.yData[-40:], np.log(np.abs(ahf2)) + imu.column("gyr_x_rad_s")[rows], atol=1e-3)
    assert not view.channels.note.isVisible()


def test_a_remembered_layout_with_bad_expressions_opens_with_those_series_off_and_said(qtbot, tmp_path):
    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    custom = {"frozen": "ahf2_roll_deg + 10**10**10", "divided": "ahf2_roll_deg + 1/0",
              "powered": "ahf2_roll_deg + 10**400", "inverted": "0**-1 * ahf2_roll_deg",
              "written_over": "log(abs(ahf2_roll_deg), imu.gyr_x_rad_s) + imu.gyr_x_rad_s",
              "doubled": "imu.gyr_x_rad_s * 2"}
    settings.setValue("channel_panes", json.dumps({"panes": [[f"custom.{n}" for n in custom]], "xy": [], "custom": custom}))
    window = MainWindow(settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(window)
    window.show()
    view = window.live_view
    view.tabs.setCurrentWidget(view.channels)  # where the remembered layout froze the window
    window.start_demo()
    channels = view.channels
    doubled = curve_of(channels, "custom.doubled")
    qtbot.waitUntil(lambda: doubled.xData is not None and len(doubled.xData) > 50, timeout=20000)
    imu = window.session.view.imu
    rows = np.searchsorted(imu.column("time_s"), doubled.xData[-40:])
    assert np.allclose(doubled.yData[-40:], 2 * imu.column("gyr_x_rad_s")[rows], atol=1e-5)
    assert channels.note.isVisible()
    said = channels.note.text().splitlines()
    assert said == [f"custom series {n} is off: {channels.disabled[n]}" for n in list(custom)[:-1]]
    assert "is inf in float64" in channels.disabled["frozen"] and "log() takes 1 value" in channels.disabled["written_over"]
    assert {k for k in channels.series if "custom" in k} == {PREFIX + "custom.doubled"}
    received = len(imu)
    qtbot.waitUntil(lambda: len(imu) > received + 50, timeout=20000)  # the reader goes on


def test_a_series_past_its_time_budget_is_switched_off_and_said(window, qtbot):
    window.start_demo()
    view = window.live_view
    channels = view.channels
    view.tabs.setCurrentWidget(channels)
    channels.budget_s = 1e-9  # below any computation's time
    channels.add_custom("slow", "sin(ahf2_roll_deg) + cos(ahf2_roll_deg)")
    channels.add("custom.slow")
    channels.add("imu.gyr_x_rad_s")
    qtbot.waitUntil(lambda: "slow" in channels.disabled, timeout=20000)
    assert channels.note.isVisible() and channels.note.text() == "custom series slow is off: took longer than 1e-09 s to compute"
    assert PREFIX + "custom.slow" not in channels.series
    gyro = curve_of(channels, "imu.gyr_x_rad_s")
    qtbot.waitUntil(lambda: gyro.xData is not None and len(gyro.xData) > 50, timeout=20000)
    drawn = len(gyro.xData)
    qtbot.waitUntil(lambda: len(gyro.xData) > drawn, timeout=20000)  # the other curves draw on

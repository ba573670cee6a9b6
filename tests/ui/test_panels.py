"""Estimator and uplink panels on the simulated bridge: a comparison estimator's curve comes and
goes, a tuned parameter reaches the estimator and the recording, the aircraft acknowledges commands."""

from groundstation.recording import open_recording
from tests.waiting import LIMIT_MS


def curve(window, quantity):
    return next(c for s, c in window.live_view.attitude.curves if s.quantity == quantity)


def test_estimator_toggle_and_live_tuning(window, qtbot):
    window.start_demo()
    session, panel = window.session, window.estimator_panel
    hf = curve(window, "hf_pitch_deg")
    assert not hf.isVisible()
    panel.shown["hf"].setChecked(True)
    qtbot.waitUntil(lambda: hf.isVisible() and hf.xData is not None and len(hf.xData) > 50, timeout=LIMIT_MS)
    assert curve(window, "hf_roll_deg").isVisible()  # both plots follow
    panel.shown["hf"].setChecked(False)
    assert not hf.isVisible() and not curve(window, "hf_roll_deg").isVisible()

    panel.boxes["hf", "beta"].setValue(0.05)
    panel.boxes["ecf", "kp"].setValue(2.5)
    panel.apply()
    assert session.pipeline.estimators["hf"].settings.beta == 0.05
    assert session.pipeline.estimators["ecf"].settings.kp == 2.5
    path = session.recording_path
    window.disconnect()
    recorded = [e for _, e in open_recording(path).events if e.get("kind") == "settings"]
    assert {"name": "hf", "settings": {"beta": 0.05}}.items() <= recorded[0].items()


def test_uplink_commands_are_acknowledged(window, qtbot):
    window.start_demo()
    uplink = window.uplink_panel
    qtbot.waitUntil(lambda: "mode both" in uplink.config_label.text(), timeout=LIMIT_MS)
    uplink.mode_box.setCurrentText("raw")
    uplink.mode_button.click()
    window.estimator_panel.boxes["ahf", "lambda_max"].setValue(1.5)
    window.estimator_panel.sendToAircraft.emit(window.estimator_panel.values("ahf"))
    qtbot.waitUntil(lambda: uplink.answers.text().count("ACK ok") == 3, timeout=LIMIT_MS)
    qtbot.waitUntil(lambda: "mode raw" in uplink.config_label.text(), timeout=LIMIT_MS)  # CONFIG follows set_mode


def test_tuned_settings_and_shown_estimators_are_remembered(window, qtbot, tmp_path):
    from groundstation.session_makers.factory import Sessions
    from groundstation.ui.main_window import MainWindow

    window.start_demo()
    window.estimator_panel.boxes["ahf", "lambda_min"].setValue(0.3)
    window.estimator_panel.apply()
    window.estimator_panel.shown["ecf"].setChecked(True)
    window.close()
    again = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(again)
    again.start_demo()
    assert again.session.pipeline.estimators["ahf"].settings.lambda_min == 0.3
    assert again.estimator_panel.shown["ecf"].isChecked() and not again.estimator_panel.shown["hf"].isChecked()


def wheel(widget, steps: int) -> None:
    from PySide6 import QtCore, QtGui, QtWidgets

    centre = QtCore.QPointF(widget.rect().center())
    event = QtGui.QWheelEvent(centre, QtCore.QPointF(widget.mapToGlobal(centre.toPoint())), QtCore.QPoint(),
                              QtCore.QPoint(0, 120 * steps), QtCore.Qt.NoButton, QtCore.Qt.NoModifier,
                              QtCore.Qt.NoScrollPhase, False)
    QtWidgets.QApplication.sendEvent(widget, event)


def test_the_mouse_wheel_passing_over_a_setting_leaves_it(window, qtbot):
    """Issue 34: scrolling over the Estimators panel changed AHF λ max from 2.000 to 1.960 unseen."""
    window.start_demo()
    box = next(iter(window.estimator_panel.boxes.values()))
    before = box.value()
    wheel(box, -4)
    assert box.value() == before
    box.setFocus()
    qtbot.waitUntil(box.hasFocus, timeout=5000)
    wheel(box, -1)  # clicked into, the wheel tunes it as a spin box does
    assert box.value() == before - box.singleStep()


def test_the_attitude_panel_names_no_estimator_when_it_shows_none(window, qtbot, recording):
    """It said "Attitude (AHF)" before any session, while the app's first estimator is AHF2, and kept the last
    session's name once it stopped."""
    from tests.ui.helpers import open_file

    panel = window.attitude_panel
    assert panel.title() == "Attitude"
    open_file(window, qtbot, recording)
    qtbot.waitUntil(lambda: panel.title() != "Attitude", timeout=LIMIT_MS)
    window.disconnect()
    assert panel.title() == "Attitude"

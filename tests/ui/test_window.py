"""Defects a new user met in the window: the uplink during a replay, where "Open recording…" starts
and the recent recordings, stale figures after the port is lost, the replay transport at its end
and on a click of its track, the export dialog's layout, disabled estimator fields, estimators
added to a replay of a recording that holds only AHF."""

import os
import threading
import time

import numpy as np
import pytest
from PySide6 import QtCore, QtWidgets

from groundstation.session_makers.load import load_session
from groundstation.sim.stream import Scenario, SimStream
from groundstation.ui.export_dialog import ExportDialog
from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow

from tests.ui.helpers import open_file, play_to_the_end
from tests.waiting import LIMIT_MS


def new_window(qtbot, tmp_path, recordings_dir):
    settings = QtCore.QSettings(str(tmp_path / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, Sessions(), recordings_dir=recordings_dir)
    qtbot.addWidget(window)
    window.show()
    return window


def test_no_uplink_control_is_enabled_when_the_source_cannot_send(window, qtbot, recording):
    open_file(window, qtbot, recording)
    assert window.session.source.can_send is False
    send = window.estimator_panel.send_button
    assert not send.isEnabled() and not window.uplink_panel.isEnabled()
    window.uplink_panel.send_ahf({"lambda_min": 0.1})  # the signal, had the button been clicked: no traceback
    window.start_demo()
    assert window.session.source.can_send is True
    assert send.isEnabled() and window.uplink_panel.isEnabled()
    # the replay's extra ones gone at once (hidden at once, deleted at Qt's next deferred deletion)
    QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.DeferredDelete)
    boxes = window.estimator_panel.findChildren(QtWidgets.QCheckBox)
    assert sorted(b.text() for b in boxes) == sorted(b.text() for b in window.estimator_panel.shown.values())


def test_open_recording_starts_in_the_recordings_folder(qtbot, tmp_path, monkeypatch):
    monkeypatch.setenv("GROUNDSTATION_RECORDINGS", str(tmp_path / "flights"))
    window = new_window(qtbot, tmp_path, None)
    dialog = window.recording_dialog()
    assert dialog.directory().absolutePath() == str(tmp_path / "flights")


def test_recent_recordings_are_listed_and_remembered(window, qtbot, tmp_path, recording):
    open_file(window, qtbot, recording)
    window.close()
    again = new_window(qtbot, tmp_path, tmp_path / "recordings")
    actions = again.recent_menu.actions()
    assert [a.text() for a in actions][0].endswith(recording.name) and actions[0].data() == str(recording)
    actions[0].trigger()
    qtbot.waitUntil(lambda: again.loading is None, timeout=LIMIT_MS)
    assert again.session.source.path == recording


def write_flight(fd: int, stop: threading.Event) -> None:
    stream = SimStream(Scenario("hover", 60.0, seed=2))
    start = time.monotonic()
    while not stop.is_set():
        for chunk in stream.advance(time.monotonic() - start):
            os.write(fd, chunk.data)
        time.sleep(0.01)


@pytest.mark.skipif(os.name != "posix", reason="a pseudo-terminal is POSIX")
def test_figures_do_not_stay_on_their_last_values_after_the_port_is_gone(window, qtbot):
    master, slave = os.openpty()
    stop = threading.Event()
    writer = threading.Thread(target=write_flight, args=(master, stop))
    writer.start()
    window.connect_serial(os.ttyname(slave), 115200)
    panel = window.link_panel
    qtbot.waitUntil(lambda: panel.values["frames/s"].text() not in ("—", "0"), timeout=LIMIT_MS)
    stop.set()
    writer.join()
    os.close(master)  # the bridge is unplugged
    qtbot.waitUntil(lambda: panel.headline.text().startswith("PORT GONE"), timeout=LIMIT_MS)
    qtbot.waitUntil(lambda: panel.values["frames/s"].text() in ("—", "0") and panel.values["bytes/s"].text() in ("—", "0"),
                    timeout=LIMIT_MS)  # once the rates' window has passed
    os.close(slave)


def test_a_new_session_does_not_show_the_previous_ones_attitude(window, qtbot, recording):
    window.start_demo()
    panel = window.attitude_panel
    qtbot.waitUntil(lambda: panel.readouts["pitch"].text() != "—", timeout=LIMIT_MS)
    window.open_recording(recording)  # computed in a worker meanwhile
    assert panel.readouts["pitch"].text() == "—" and panel.indicator.pitch_deg != panel.indicator.pitch_deg  # NaN


def test_the_replay_ends_with_a_replay_button_that_plays_it_again(window, qtbot, recording):
    open_file(window, qtbot, recording)
    bar = window.replay_bar
    play_to_the_end(window, qtbot)
    qtbot.waitUntil(lambda: bar.play_button.text() == "Replay", timeout=LIMIT_MS)
    assert len(window.session.view.imu) == len(window.session.data.tables["imu"]["time_s"])  # every row shown
    bar.speed_box.setCurrentIndex(bar.speed_box.findData(1.0))
    bar.play_button.click()
    assert window.session.running and window.session.source.position_s == 0.0 and bar.play_button.text() == "Pause"
    qtbot.waitUntil(lambda: window.session.source.position_s > 0.2, timeout=LIMIT_MS)  # playing again
    assert len(window.session.view.imu) < 100


def test_a_click_on_the_slider_track_seeks_there(window, qtbot, recording):
    open_file(window, qtbot, recording)
    bar = window.replay_bar
    duration = window.session.source.duration_s
    with qtbot.waitSignal(bar.seekRequested, timeout=2000) as seek:
        qtbot.mouseClick(bar.slider, QtCore.Qt.LeftButton, pos=QtCore.QPoint(int(bar.slider.width() * 0.75), bar.slider.height() // 2))
    assert seek.args[0] == pytest.approx(0.75 * duration, abs=0.05 * duration)


def test_the_export_dialog_keeps_its_fields_when_the_result_appears(qtbot, recording):
    dialog = ExportDialog(load_session, recording, 30.0)
    qtbot.addWidget(dialog)
    dialog.show()
    qtbot.waitExposed(dialog)
    before = {w: w.height() for w in (dialog.format_box, dialog.path_edit, dialog.t_from, dialog.rate, dialog.progress)}
    dialog.status.setText("wrote " + "/a/rather/long/path/to/the/exported/file/of/a/flight " * 4 + "(36,001 rows, 12 columns)")
    qtbot.wait(100)
    assert {w: w.height() for w in before} == before


def test_fields_of_an_estimator_the_session_lacks_show_no_number(window, qtbot, recording):
    open_file(window, qtbot, recording)  # the recording holds AHF only
    box = window.estimator_panel.boxes["hf", "beta"]
    assert not box.isEnabled() and box.text() in ("", "—")
    assert window.estimator_panel.boxes["ahf", "lambda_min"].text().endswith("rad/s")


def test_an_estimator_added_to_a_replay_recomputes_it_with_the_settings_asked(window, qtbot, recording):

    open_file(window, qtbot, recording)
    panel = window.estimator_panel
    assert "hf" in panel.shown and "hf" not in window.session.view.filters
    window.replay_bar.play_button.click()  # paused: the what-if keeps the position
    window.seek(12.0)
    panel.shown["hf"].setChecked(True)  # add HF to the replay: the file is computed again with it
    assert window.loading_row.isVisible()
    qtbot.waitUntil(lambda: window.loading is None and "hf" in window.session.view.filters, timeout=LIMIT_MS)
    assert window.session.source.position_s == 12.0 and window.session.source.paused
    panel = window.estimator_panel
    assert panel.boxes["hf", "beta"].isEnabled()
    panel.boxes["hf", "beta"].setValue(0.2)
    panel.apply()  # the what-if: computed again with HF's beta forced
    qtbot.waitUntil(lambda: window.loading is None and window.session.view.settings()["hf"]["beta"] == 0.2,
                    timeout=LIMIT_MS)
    assert window.session.source.position_s == 12.0
    play_to_the_end(window, qtbot)
    shown = window.session.view.imu.to_dict()
    headless = load_session(recording, ("ahf", "hf"), {"hf": {"beta": 0.2}}).tables["imu"]  # the CLI's --set
    assert list(shown) == list(headless)
    for name, column in headless.items():
        np.testing.assert_array_equal(shown[name], column, err_msg=name)
    assert "HF" in window.live_view.attitude.visible_labels()

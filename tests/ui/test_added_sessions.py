"""The sessions added beside the window's own (issue 34, the teacher with a class of boards), as fully
the window's as its own: each one's heading on the Heading tab in its pen style; the Estimators panel
tunes the session selected (in the Sessions tab or its own box), that session only, its recording
carrying the change; its channels usable in a custom series' expression ("S2:imu.gyr_x_dps"), which a
removed session's name switches off with a reason.

One window for the module (the demo and a second simulated board beside it): the boards fly while the
tests look, the last one removes the board."""

import time

import numpy as np
import pytest
from PySide6 import QtCore
from scipy.spatial.transform import Rotation

from groundstation.recording import open_recording
from groundstation.session_makers.factory import Sessions
from groundstation.ui.channels import PREFIX
from groundstation.ui.custom_series import CUSTOM
from groundstation.ui.main_window import MainWindow

from tests.ui.helpers import export_csv
from tests.waiting import LIMIT_MS, LIMIT_S


def process_until(condition) -> None:
    """The Qt event loop run (the window's timer ticking) until ``condition`` holds."""
    deadline = time.monotonic() + LIMIT_S
    while not condition():
        assert time.monotonic() < deadline, f"not within {LIMIT_S:g} s"
        QtCore.QCoreApplication.processEvents(QtCore.QEventLoop.AllEvents, 50)
        time.sleep(0.01)


@pytest.fixture(scope="module")
def boards(qapp, tmp_path_factory):
    """The window on the demo, a second simulated board (S2) beside it, both placed on the time axis."""
    folder = tmp_path_factory.mktemp("boards")
    settings = QtCore.QSettings(str(folder / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, Sessions(), recordings_dir=folder / "recordings")
    window.show()
    window.start_demo()
    board = window.session_list.add_source("sim:?seed=7")
    assert board is not None and board.label == "S2", window.banner.text()
    process_until(lambda: board.offset_s is not None and len(window.session.view.imu) > 200)
    yield window, board
    window.close()
    window.session_list.stop_all()


def curve(plots, label):
    return next(c for spec, c in plots.curves if spec.label == label)


def heading_deg(table, prefix: str = "") -> tuple[np.ndarray, np.ndarray]:
    """Time and heading (0..360°) of a table's quaternion (columns ``{prefix}qw`` ...: ``ahf2_`` in an IMU
    table, none in the onboard one), by scipy from its quaternions (w first)."""
    rows = table.to_dict()
    q_xyzw = np.column_stack([rows[f"{prefix}q{c}"] for c in "xyzw"])
    return rows["time_s"], Rotation.from_quat(q_xyzw).as_euler("ZYX", degrees=True)[:, 0] % 360.0


def test_each_session_has_its_heading_in_its_pen_style(boards, qtbot):
    window, board = boards
    view = window.live_view
    view.tabs.setCurrentWidget(view.heading)
    labels = {spec.label for spec, _ in view.heading.curves}
    # AHF2's yaw is the gyro's alone, no heading (``gives_heading``): the onboard heading is S2's shown one
    assert {"onboard", "S2 onboard"} <= labels and not {"AHF2", "S2 AHF2"} & labels
    pen = lambda plots, label: curve(plots, label).opts["pen"].style()  # noqa: E731
    # as on the Attitude tab, and not the window's own
    assert pen(view.heading, "S2 onboard") == pen(view.attitude, "S2 onboard") != pen(view.heading, "onboard")
    s2 = curve(view.heading, "S2 onboard")
    qtbot.waitUntil(lambda: len(view.heading.drawn(s2)[0]) > 50, timeout=LIMIT_MS)
    t, drawn = view.heading.drawn(s2)
    with board.session.lock:
        own_t, own_deg = heading_deg(board.session.view.onboard)
    rows = np.searchsorted(own_t, t - board.offset_s - 1e-6)  # each drawn sample's row (its time, less rounding)
    kept = (rows < len(own_t)) & np.isfinite(drawn)  # a gap is a NaN between rows
    np.testing.assert_allclose(own_t[rows[kept]] + board.offset_s, t[kept], atol=1e-6)  # its rows, on the window's axis
    error = np.abs((drawn[kept] - own_deg[rows[kept]] + 180.0) % 360.0 - 180.0)
    assert error.max() < 1e-3  # float32 in the plots


def test_the_estimators_panel_tunes_the_session_selected_and_that_one_only(boards, qtbot, tmp_path):
    window, board = boards
    panel, sessions = window.estimator_panel, window.session_list
    main = window.session
    assert panel.session is main and panel.session_box.currentText().startswith("main: ")
    window.controls.setCurrentWidget(sessions)
    sessions.tree.setCurrentItem(sessions.tree.topLevelItem(1))  # a click on S2's row
    assert panel.session is board.session and panel.session_box.currentText().startswith("S2: ")
    assert not panel.send_button.isEnabled()  # the Uplink tab is the window's session's
    before = {"main": main.view.settings()["hf"]["beta"], "S2": board.session.view.settings()["hf"]["beta"]}
    panel.boxes["hf", "beta"].setValue(before["S2"] * 2)
    panel.apply()
    assert panel.message.text() == f"applied to S2: HF β = {before['S2'] * 2:g}"
    assert board.session.view.settings()["hf"]["beta"] == before["S2"] * 2
    assert main.view.settings()["hf"]["beta"] == before["main"]  # the window's own untouched
    # Its recording carries the change, so its replay and export compute with it; the window's has none.
    changes = lambda session: [(e["name"], e["settings"]) for _, e in open_recording(session.recording_path).events  # noqa: E731
                               if e.get("kind") == "settings"]
    qtbot.waitUntil(lambda: bool(changes(board.session)), timeout=LIMIT_MS)  # written as the recording goes on
    assert changes(board.session) == [("hf", {"beta": before["S2"] * 2})] and changes(main) == []
    # Its export (the Sessions tab's Export...) computes HF as the board did: β doubled from the change on.
    with board.session.lock:
        changed_s = board.session.view.imu.tail(1)[0, board.session.view.imu.columns.index("time_s")]
    qtbot.waitUntil(lambda: len(board.session.view.imu) and board.session.file()[1] > changed_s + 1.5, timeout=LIMIT_MS)
    exported = export_csv(window, qtbot, sessions, 1, tmp_path / "s2.csv")
    with board.session.lock:
        live = board.session.view.imu.to_dict()
    rows = np.searchsorted(live["time_s"], exported["time_s"].to_numpy() - 1e-9)
    kept = rows < len(live["time_s"])
    np.testing.assert_allclose(live["time_s"][rows[kept]], exported["time_s"][kept], atol=1e-9)
    assert (exported["time_s"][kept] > changed_s + 0.5).sum() > 50
    for c in "wxyz":
        np.testing.assert_allclose(exported[f"hf_q{c}"][kept], live[f"hf_q{c}"][rows[kept]], rtol=0, atol=1e-9)
    # Its comparison estimators shown in its own pen style ("S2 HF"), the window's own HF not.
    panel.shown["hf"].setChecked(True)
    attitude = window.live_view.attitude
    assert "S2 HF" in attitude.visible_labels() and "HF" not in attitude.visible_labels()
    assert curve(attitude, "S2 HF").opts["pen"].style() == curve(attitude, "S2 AHF2").opts["pen"].style()
    # The panel's own box chooses the session too, and says it.
    panel.session_box.activated.emit(0)
    assert sessions.selected() is None and panel.session is main and not panel.shown["hf"].isChecked()
    assert panel.boxes["hf", "beta"].value() == pytest.approx(before["main"])


def test_an_added_file_is_computed_again_with_the_settings_applied_to_it(boards, qtbot, recording):
    window, _ = boards
    panel = window.estimator_panel
    log = window.session_list.add_file(recording)
    qtbot.waitUntil(lambda: log.session is not None and log.offset_s is not None, timeout=LIMIT_MS)
    first = log.session
    panel.session_box.setCurrentIndex(2)  # chosen in the panel's own box
    panel.session_box.activated.emit(2)
    assert window.session_list.selected() is log and panel.session is first and panel.replay
    assert "ahf" in first.view.filters, first.view.filters
    main_max, lam_max = (s.view.settings()["ahf"]["lambda_max"] for s in (window.session, first))
    panel.boxes["ahf", "lambda_max"].setValue(lam_max / 2)
    panel.apply()
    assert panel.message.text() == "recomputing S3 with these settings…"
    qtbot.waitUntil(lambda: log.session is not first, timeout=LIMIT_MS)
    assert panel.session is log.session  # the panel on the new computation
    assert log.session.view.settings()["ahf"]["lambda_max"] == log.session.setup[1]["ahf"]["lambda_max"] == lam_max / 2
    assert window.session.view.settings()["ahf"]["lambda_max"] == main_max  # the window's own untouched
    dialog = window.session_list.export_selected()
    assert dialog.setup == log.session.setup  # its export computes with them
    dialog.close()
    with log.session.lock, first.lock:
        again, before = log.session.view.imu.to_dict(), first.view.imu.to_dict()
    n = min(len(again["time_s"]), len(before["time_s"]))
    assert n > 100
    assert np.array_equal(again["gyr_x_rad_s"][:n], before["gyr_x_rad_s"][:n])  # the same samples
    assert not np.allclose(again["ahf_qw"][:n], before["ahf_qw"][:n], rtol=0, atol=1e-9)  # AHF with its new λ max


def test_a_custom_series_names_another_sessions_channels_until_it_is_removed(boards, qtbot):
    """Last: it removes the board. "S2:imu.gyr_x_rad_s" as the Channels tab lists it; its rows on the
    window's axis, the window's own gyroscope taken at or before each; S2 removed, the series is off and says why."""
    window, board = boards
    channels = window.live_view.channels
    window.live_view.tabs.setCurrentWidget(channels)
    dialog = channels.new_custom()
    dialog.name.setText("gyro_x_difference_dps")
    dialog.expression.setText("degrees(S2:imu.gyr_x_rad_s) - gyr_x_dps")
    dialog.accept()
    assert dialog.result() == dialog.DialogCode.Accepted, dialog.message.text()
    channels.add(f"{CUSTOM}.gyro_x_difference_dps")
    series = channels.series[f"{PREFIX}{CUSTOM}.gyro_x_difference_dps"]
    qtbot.waitUntil(lambda: series.taken > 200, timeout=LIMIT_MS)
    t, got = series.data("gyro_x_difference_dps", None)
    with board.session.lock:
        s2 = board.session.view.imu.to_dict()
    with window.session.lock:
        own = window.session.view.imu.to_dict()
    rows = np.searchsorted(s2["time_s"] + board.offset_s, t - 1e-6)  # S2's rows, on the window's axis
    before = np.searchsorted(own["time_s"], t, side="right") - 1  # the window's newest row at or before each
    kept = (rows < len(s2["time_s"])) & (before >= 0) & np.isfinite(got)
    assert kept.sum() > 100
    expected = np.degrees(s2["gyr_x_rad_s"][rows[kept]]) - np.degrees(own["gyr_x_rad_s"][before[kept]])
    np.testing.assert_allclose(got[kept], expected, atol=1e-3)  # float32 in the series

    window.session_list.remove(board)
    why = "unknown channel 'S2:imu.gyr_x_rad_s': there is no session S2 in this window"
    assert channels.note.isVisible() and channels.note.text() == f"custom series gyro_x_difference_dps is off: {why}"
    assert f"{PREFIX}{CUSTOM}.gyro_x_difference_dps" not in channels.series
    frames = window.live_view.frames_drawn
    qtbot.waitUntil(lambda: window.live_view.frames_drawn > frames + 3, timeout=LIMIT_MS)  # the window draws on
    again = channels.new_custom()
    again.name.setText("again")
    again.expression.setText("S2:imu.gyr_x_rad_s")
    again.accept()
    assert again.isVisible() and again.message.text() == why  # the dialog says it, and stays
    again.reject()

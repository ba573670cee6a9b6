"""Every estimator in the app: the magnetometer- and GPS-aided ones (HF+mag, ECF+mag, MCF, UKF, SSSRUKF)
run on the demo and on a replay of the app's recording (and in its export), start hidden,
get a "show" check box each (four per row), are drawn only when shown, appear on the Heading tab, and
HF+mag's yaw follows the demo's compass."""

import numpy as np
import pytest

from groundstation import quaternion
from groundstation.recording import RecordingWriter
from groundstation.estimation import ESTIMATORS, label, live_estimators
from groundstation.session_makers.load import load_session
from groundstation.session_makers.factory import DEMO_SPEC, Sessions
from groundstation.sim.stream import SimStream
from groundstation.sources import parse_spec
from groundstation.sources.sim import parse_scenario
from groundstation.ui.export_job import ExportJob
from groundstation.ui.estimator_panel import SHOWN_COLUMNS
from groundstation.ui.main_window import MainWindow

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS

NEW = ("hfm", "ecfm", "mcf", "ukf", "sssrukf")
LIVE_FILTERS = live_estimators()
COMPARED = LIVE_FILTERS[1:]  # the first is shown; the others get a "show" box


def points(curve) -> int:
    return 0 if curve.xData is None else len(curve.xData)


def curves(plots, label):
    return [c for s, c in plots.curves if s.label == label]


def angle_between_deg(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0)


def imu_rows(window) -> dict[str, np.ndarray]:
    with window.session.lock:
        return window.session.view.imu.to_dict()


def test_new_estimators_run_start_hidden_and_toggle_on_the_demo(window, qtbot):
    assert set(NEW) <= set(LIVE_FILTERS)
    window.start_demo()
    view, panel = window.live_view, window.estimator_panel
    assert window.session.view.filters == LIVE_FILTERS
    assert list(panel.shown) == list(COMPARED)  # one box per comparison estimator, none checked
    assert [n for n, box in panel.shown.items() if box.isChecked()] == []  # the paper's AHF one click away (issue 34)
    assert {name: panel.shown[name].text() for name in NEW} == {
        "hfm": "HF+mag", "ecfm": "ECF+mag", "mcf": "MCF", "ukf": "UKF", "sssrukf": "SSSRUKF"}
    positions = [panel._shown_row.getItemPosition(panel._shown_row.indexOf(box))[:2] for box in panel.shown.values()]
    assert positions == [divmod(i, SHOWN_COLUMNS) for i in range(len(COMPARED))]
    assert {(name, setting) for name, setting in panel.boxes if name in NEW} == {
        ("hfm", "beta"), ("ecfm", "kp"), ("ecfm", "ki")}

    qtbot.waitUntil(lambda: view.frames_drawn > 20 and len(window.session.view.imu) > 300, timeout=LIMIT_MS)
    rows = imu_rows(window)
    for name in NEW:  # the columns fill: unit quaternions from the start
        q = np.column_stack([rows[f"{name}_q{c}"] for c in "wxyz"])
        assert np.all(np.isfinite(q)), name
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    for name in NEW:  # hidden: not drawn at all, on either tab
        for plots in (view.attitude, view.heading):
            assert all(not c.isVisible() and points(c) == 0 for c in curves(plots, label(name))), name

    view.tabs.setCurrentWidget(view.heading)
    for name in NEW:
        panel.shown[name].setChecked(True)
        shown_as = label(name)
        heading = curves(view.heading, shown_as)[0]
        qtbot.waitUntil(lambda: points(heading) > 50, timeout=LIMIT_MS)
        assert all(c.isVisible() for c in curves(view.attitude, shown_as) + curves(view.heading, shown_as))
        assert shown_as in view.heading.read_at(float(heading.xData[-1]))  # the crosshair reads it too
        panel.shown[name].setChecked(False)
        assert not any(c.isVisible() for c in curves(view.attitude, shown_as) + curves(view.heading, shown_as))
        assert shown_as not in view.attitude.visible_labels()
    view.tabs.setCurrentWidget(view.attitude)  # shown now, the attitude plots draw it too
    panel.shown["ukf"].setChecked(True)
    qtbot.waitUntil(lambda: points(curves(view.attitude, "UKF")[0]) > 50, timeout=LIMIT_MS)
    window.grab()  # the two-row legend and the grid of boxes paint


def test_hfm_yaw_follows_the_compass_on_the_demo(window, qtbot):
    window.start_demo()
    pipeline = window.session.view
    qtbot.waitUntil(lambda: len(pipeline.imu) > 800 and len(pipeline.tables["mag_raw"]) > 400, timeout=LIMIT_MS)
    rows = imu_rows(window)
    with window.session.lock:
        mag = pipeline.tables["mag_raw"].to_dict()
    q = np.column_stack([rows[f"hfm_q{c}"] for c in "wxyz"])
    yaw_deg = np.degrees(quaternion.to_euler_zyx(q)[:, 0]) % 360.0
    later = mag["time_s"] > rows["time_s"][0] + 2.0  # the first seconds settle
    at = np.clip(np.searchsorted(rows["time_s"], mag["time_s"][later]), 0, len(yaw_deg) - 1)
    error = angle_between_deg(yaw_deg[at], mag["heading_deg"][later])
    assert later.sum() > 200
    assert np.median(error) < 5.0 and np.percentile(error, 95) < 15.0
    assert np.ptp(np.unwrap(np.radians(mag["heading_deg"][later]))) > np.radians(5)  # the craft did turn
    view = window.live_view
    view.tabs.setCurrentWidget(view.heading)
    window.estimator_panel.shown["hfm"].setChecked(True)
    hfm = curves(view.heading, "HF+mag")[0]
    qtbot.waitUntil(lambda: points(hfm) > 50, timeout=LIMIT_MS)
    assert np.all((hfm.yData >= 0) & (hfm.yData < 360))  # the Heading tab's 0..360°


@pytest.fixture(scope="module")
def app_recording(tmp_path_factory):
    """20 s of the demo's flight (magnetometer, barometer, GPS) recorded as the app records: every estimator."""
    path = tmp_path_factory.mktemp("app") / "demo.gsrec"
    stream = SimStream(parse_scenario(parse_spec(f"{DEMO_SPEC}?duration=20&seed=3")))
    with RecordingWriter(path, {"source": "test", "filters": list(LIVE_FILTERS)}) as writer:
        for chunk in stream.advance(20.0):
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
    return path


def test_a_replay_and_its_export_carry_every_estimator(window, qtbot, app_recording, tmp_path):
    open_file(window, qtbot, app_recording)
    window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(64.0))
    qtbot.waitUntil(lambda: not window.session.running, timeout=LIMIT_MS)
    assert window.session.view.filters == LIVE_FILTERS
    rows = imu_rows(window)
    for name in NEW:
        assert len(rows[f"{name}_qw"]) > 1500 and np.all(np.isfinite(rows[f"{name}_qw"])), name
    offered = list(window.estimator_panel.shown)  # the recorded ones, then those a replay can add
    assert offered[: len(COMPARED)] == list(COMPARED) and set(offered[len(COMPARED) :]) == set(ESTIMATORS) - set(LIVE_FILTERS)
    assert not any(window.estimator_panel.shown[name].isChecked() for name in NEW)
    window.estimator_panel.shown["mcf"].setChecked(True)
    mcf = curves(window.live_view.attitude, "MCF")[0]
    qtbot.waitUntil(lambda: points(mcf) > 0, timeout=LIMIT_MS)  # drawn on switching on, with nothing new arriving

    out = tmp_path / "demo.csv"
    job = ExportJob(load_session, app_recording, out).start()
    job.wait(60)
    assert job.done and job.error is None, job.error
    header = out.read_text().splitlines()[0]
    assert all(name in header for name in NEW), header


def test_settings_from_before_the_new_estimators_keep_them_hidden(window, qtbot, tmp_path):
    window.settings.setValue("hidden_curves", ["ECF"])  # stored by a version with AHF, HF and ECF only
    again = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(again)
    again.start_demo()
    shown = again.estimator_panel.shown
    assert shown["hf"].isChecked() and not shown["ecf"].isChecked()  # the user's choice stands
    assert not any(shown[name].isChecked() for name in NEW)
    shown["ukf"].setChecked(True)
    again.close()
    third = MainWindow(window.settings, Sessions(), recordings_dir=tmp_path / "recordings")
    qtbot.addWidget(third)
    third.start_demo()
    assert third.estimator_panel.shown["ukf"].isChecked() and not third.estimator_panel.shown["mcf"].isChecked()


def test_a_gps_aided_estimator_shown_without_gps_is_said_to_need_it(window, qtbot):
    """Issue 33: shown on a session without GPS, UKF says in the panel why it is little use; with GPS it does not."""
    window.connect_serial("sim:?sensors=mag")
    qtbot.waitUntil(lambda: window.session is not None and len(window.session.view.imu) > 50, timeout=LIMIT_MS)
    panel = window.estimator_panel
    panel.shown["ukf"].setChecked(True)
    assert "ukf needs GPS velocity and heading" in panel.message.text()
    panel.shown["ukf"].setChecked(False)
    panel.message.clear()
    window.start_demo()  # the demo has GPS
    qtbot.waitUntil(lambda: window.session.source.description.startswith("simulated")
                    and len(window.session.view.tables.get("gps", ())) > 0, timeout=LIMIT_MS)
    window.estimator_panel.shown["ukf"].setChecked(True)
    assert "needs" not in window.estimator_panel.message.text()

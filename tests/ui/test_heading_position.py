"""Heading and position in the window: the heading readout, the Heading tab and the Position tab
follow the pipeline's magnetometer, barometer and GPS tables (and the simulator's truth within the
GPS noise); a session without those sensors shows "—" and no extra tabs; the demo carries them all."""

import math

import numpy as np
import pytest

from groundstation import geodesy, quaternion
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.extra_sensors import AuxSettings
from groundstation.sim.profiles import make_profile
from groundstation.ui.navigation import heading_now, newest_row

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS

DURATION_S, SEED = 20, 3
GPS_NOISE_M = AuxSettings().gps_position_noise_m


@pytest.fixture(scope="module")
def aided_recording(tmp_path_factory):
    """20 s of simulated flight with magnetometer (50 Hz), barometer (25 Hz) and GPS (5 Hz)."""
    from groundstation.cli import main

    path = tmp_path_factory.mktemp("aided") / "aided.gsrec"
    args = ["simulate", "--scenario", "flight", "--duration", str(DURATION_S), "--seed", str(SEED),
            "--sensors", "mag,baro,gps", "--out", str(path)]
    assert main(args) == 0
    return path


def replay_to_the_end(window, qtbot, path) -> Pipeline:
    open_file(window, qtbot, path)
    bar = window.replay_bar
    bar.speed_box.setCurrentIndex(bar.speed_box.findData(64.0))
    qtbot.waitUntil(lambda: not window.session.running, timeout=LIMIT_MS)
    return window.session.view


def points(curve) -> int:
    return 0 if curve.xData is None else len(curve.xData)  # pyqtgraph keeps None for no data


def angle_between_deg(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def test_readouts_and_plots_follow_the_tables_and_the_truth(window, qtbot, aided_recording):
    pipeline = replay_to_the_end(window, qtbot, aided_recording)
    view, gps = window.live_view, newest_row(pipeline.tables["gps"])
    qtbot.waitUntil(lambda: window.attitude_panel.readouts["heading"].text() == f"{gps['heading_deg']:5.1f}° GPS",
                    timeout=LIMIT_MS)
    first_device_s = pipeline.imu.column("device_time_us")[0] / 1e6 - pipeline.imu.column("time_s")[0]
    truth = make_profile("flight", DURATION_S, SEED).truth(pipeline.tables["gps"].column("time_s") + first_device_s)
    true_yaw_deg = math.degrees(quaternion.to_euler_zyx(truth.q_body_to_ned[-1])[0])
    assert angle_between_deg(gps["heading_deg"], true_yaw_deg) < 3.0  # σ 0.5°
    assert view.tabs.isTabVisible(view.tabs.indexOf(view.heading))
    assert view.tabs.isTabVisible(view.tabs.indexOf(view.position))

    view.tabs.setCurrentWidget(view.heading)  # drawn when shown
    compass = next(c for s, c in view.heading.curves if s.label == "compass")
    gps_heading = next(c for s, c in view.heading.curves if s.label == "GPS")
    newest_s = newest_row(pipeline.tables["mag_raw"])["time_s"]  # the plots take the rows a tick after the pipeline
    qtbot.waitUntil(lambda: compass.xData is not None and compass.xData[-1] == newest_s, timeout=LIMIT_MS)
    assert compass.yData[-1] == np.float32(newest_row(pipeline.tables["mag_raw"])["heading_deg"] % 360.0)
    assert gps_heading.yData[-1] == np.float32(gps["heading_deg"])

    view.tabs.setCurrentWidget(view.position)
    readouts = {name: label.text() for name, label in view.position.readouts.items()}
    assert readouts["latitude"] == f"{gps['lat_deg']:.7f}°" and readouts["longitude"] == f"{gps['lon_deg']:.7f}°"
    assert readouts["altitude (MSL)"] == f"{gps['alt_m']:.1f} m"
    assert readouts["ground speed"] == f"{math.hypot(gps['vel_n_m_s'], gps['vel_e_m_s']):.1f} m/s"
    assert readouts["satellites"] == "10" and readouts["fix"] == "3D"
    baro = pipeline.tables["baro"].to_dict()
    baro_height_m = geodesy.pressure_altitude_m(baro["pressure_Pa"][-1], baro["pressure_Pa"][0], baro["temperature_degC"][0])
    assert abs(float(readouts["height (barometer)"].removesuffix(" m")) - baro_height_m) < 0.051
    assert not view.position.note.isVisible()

    fixes = pipeline.tables["gps"].to_dict()
    ned = geodesy.ned_from_geodetic(fixes["lat_deg"], fixes["lon_deg"], fixes["alt_m"],
                                    (fixes["lat_deg"][0], fixes["lon_deg"][0], fixes["alt_m"][0]))
    east, north = view.position.tracks["gps"].getData()
    assert len(east) == len(ned)  # the whole flight, every fix
    np.testing.assert_allclose(np.column_stack([north, east]), ned[:, :2], atol=1e-3)  # float32 metres
    true_track = truth.pos_ned_m[:, :2] - truth.pos_ned_m[0, :2]
    assert np.max(np.abs(np.column_stack([north, east]) - true_track)) < 6 * GPS_NOISE_M  # two fixes' noise
    assert np.ptp(true_track[:, 0]) + np.ptp(true_track[:, 1]) > 10.0  # the craft did travel
    height = next(c for s, c in view.position.height.curves if s.label == "barometer")
    assert abs(float(height.yData[-1]) - baro_height_m) < 1e-3
    fused = pipeline.tables.get("position")
    if fused is not None and len(fused):  # a fused position estimate, when the pipeline makes one
        assert points(view.position.tracks["position"]) > 0


def test_a_session_without_aiding_sensors_shows_a_dash(window, qtbot, recording):
    open_file(window, qtbot, recording)
    view, panel = window.live_view, window.attitude_panel
    qtbot.waitUntil(lambda: view.frames_drawn > 5 and panel.readouts["yaw"].text() != "—", timeout=LIMIT_MS)
    assert panel.readouts["heading"].text() == "—"
    assert not view.tabs.isTabVisible(view.tabs.indexOf(view.heading))
    assert not view.tabs.isTabVisible(view.tabs.indexOf(view.position))
    view.position.draw(view.series, view.window_s, None)  # drawing the hidden tab anyway breaks nothing
    assert not view.position.note.isHidden()  # "no GPS" (the tab itself is hidden)
    assert {label.text() for label in view.position.readouts.values()} == {"—"}
    assert points(view.position.tracks["gps"]) == 0
    window.grab()


def test_the_demo_shows_heading_and_position(window, qtbot):
    window.start_demo()
    view = window.live_view
    qtbot.waitUntil(lambda: view.tabs.isTabVisible(view.tabs.indexOf(view.position))
                    and window.attitude_panel.readouts["heading"].text().endswith("GPS"), timeout=LIMIT_MS)
    tables = window.session.view.tables
    assert len(tables["mag_raw"]) and len(tables["baro"]) and len(tables["gps"])
    view.tabs.setCurrentWidget(view.position)
    qtbot.waitUntil(lambda: view.position.readouts["fix"].text() == "3D", timeout=LIMIT_MS)
    hf_heading = next(c for s, c in view.heading.curves if s.label == "HF+mag")  # a heading estimator (it takes the magnetometer)
    assert not hf_heading.isVisible()  # the comparison estimators start switched off, here too
    window.estimator_panel.shown["hfm"].setChecked(True)
    assert hf_heading.isVisible()


def test_heading_falls_back_to_the_compass_and_goes_stale():
    pipeline = Pipeline()
    assert heading_now(pipeline) is None
    gps, mag = pipeline.tables["gps"], pipeline.tables["mag_raw"]
    row = dict.fromkeys(gps.columns, 0.0) | {"time_s": 1.0, "heading_deg": 655.35, "fix_type": 3.0}  # 0xFFFF: none
    gps.append(list(row.values()))
    mag.append([1.0, 0.0, 20.0, 0.0, 45.0, -30.0])
    assert heading_now(pipeline) == (330.0, "compass")
    gps.append(list((row | {"time_s": 1.1, "heading_deg": 12.5}).values()))
    assert heading_now(pipeline) == (12.5, "GPS")
    gps.append(list((row | {"time_s": 5.0, "fix_type": 0.0}).values()))  # the fix is lost; the compass is 4 s old
    assert heading_now(pipeline) is None

"""The shared real logs (../shared/datasets/flightlogs, README there): each opens with the streams,
rates and durations the README lists; the onboard attitude's range matches the flight it describes;
the host filters agree with the autopilot's estimate where the IMU is fast enough, and the SITL
truth scores both. Large files are cut to their start to keep each test within seconds."""

import numpy as np
import pytest

from groundstation.autopilot.agreement import onboard_agreement, pitch_roll_rad
from groundstation.session_makers.flight_log_session import read_log
from groundstation.session_makers.flight_log_session import load_log
from groundstation.export.columns import export_columns

from mavlink_helpers import flightlog


def trimmed(tmp_path, name, size):
    path = tmp_path / name
    path.write_bytes(flightlog(name).read_bytes()[:size])
    return path


def test_arducopter_dataflash_flight():
    data = load_log(flightlog("arducopter_cubeorange_2023-07-06_10-12-18.bin"), ["hf"])
    meta = data.metadata
    assert meta["autopilot"] == "ArduPilot" and meta["imu_rate_hz"] == pytest.approx(25.0, rel=0.01)
    assert data.time_s[-1] == pytest.approx(98.0, abs=0.5) and "imu_warning" not in meta
    pitch, roll = np.degrees(pitch_roll_rad(data.quaternion("onboard")))
    # README: roll up to 44 degrees and pitch up to 30 in LOITER/RTL.
    assert np.nanmax(np.abs(roll)) == pytest.approx(44, abs=3) and np.nanmax(np.abs(pitch)) == pytest.approx(30, abs=3)
    agree = onboard_agreement(data)["hf"]
    assert agree["pitch_rms_deg"] < 5.0 and agree["roll_rms_deg"] < 5.0  # measured 3.4 / 3.7 at 25 Hz
    assert np.nanmax(data.tables["gps"]["satellites"]) in (21, 22) and np.nanmax(data.tables["gps"]["fix_type"]) == 3


def test_arduplane_dataflash_without_imu_opens_with_the_onboard_attitude_only():
    data = load_log(flightlog("arduplane_omnibusf4_ground_pilot_0004.bin"))
    assert data.estimated == () and data.sample_table == "onboard" and len(data) == 2375
    assert "no IMU" in data.metadata["notes"]
    assert data.time_s[-1] == pytest.approx(99.4, abs=0.5)


def test_px4_bench_log_old_layout_at_250_hz_agrees_while_still():
    log = read_log(flightlog("px4_auavx21_bench_sample.ulg"))
    assert log.imu.rate_hz == pytest.approx(250.0, rel=0.01) and log.onboard.rate_hz == pytest.approx(83, rel=0.05)
    assert log.mag.source == "sensor_combined" and log.gps is None and log.baro is None  # README: no baro found
    data = load_log(log.path, ["ecf"])
    agree = onboard_agreement(data)["ecf"]
    assert agree["pitch_rms_deg"] < 0.5 and agree["roll_rms_deg"] < 0.5  # on a bench: measured 0.11 / 0.12


def test_px4_modern_log_attitude_starts_late():
    data = load_log(flightlog("px4_fmuv5_quad_hop.ulg"), ["hf"])
    have = np.isfinite(data.quaternion("onboard")[:, 0])
    assert not have[: int(3.0 * 200)].any()  # README: vehicle_attitude only for the last 5.6 s
    assert have.sum() / 200 == pytest.approx(5.55, abs=0.1)
    assert onboard_agreement(data)["hf"]["rows"] == have.sum()
    assert {"mag_x_uT", "baro_pressure_Pa", "gps_lat_deg"} <= export_columns(data).keys()


def test_px4_sitl_truth_scores_the_onboard_and_host_estimates():
    data = load_log(flightlog("px4_sitl_quad_groundtruth.ulg"), ["ecf"])
    errors = data.evaluate()
    # The autopilot's own estimate against the simulator's truth, both from the log: this checks our
    # quaternion conventions independently of the host filters.
    assert errors["onboard"]["incl_rmse_deg"] < 0.5  # measured 0.16
    assert errors["ecf"]["incl_rmse_deg"] < 0.5  # measured 0.09 at 200 Hz


def test_ardusub_tlog_imu_too_slow_and_the_autopilot_among_four_senders(tmp_path):
    data = load_log(trimmed(tmp_path, "ardusub_rov_surface.tlog", 300_000))
    assert data.metadata["autopilot"] == "ArduPilot"  # not the camera, companion or GCS heartbeats
    assert "2.0 Hz" in data.metadata["imu_warning"] and "too slow" in data.metadata["imu_warning"]
    assert "onboard stream" in data.metadata and "20.0 Hz" in data.metadata["onboard stream"]


def test_quadplane_tlog_mavlink1(tmp_path):
    log = read_log(trimmed(tmp_path, "arduplane_quadplane_sitl.tlog", 300_000))
    assert log.imu.rate_hz == pytest.approx(4.17, rel=0.02) and log.onboard.source == "ATTITUDE"
    assert "SIMSTATE" in log.tables and log.units["VFR_HUD"]["airspeed"] == "m/s"

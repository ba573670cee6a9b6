"""PX4 .ulg: a file written here from the ULog specification (values from the simulator's truth), read
back through the importer; the host filters scored against that truth and against the onboard copy."""

import numpy as np
import pytest

from groundstation.autopilot.agreement import onboard_agreement
from groundstation.session_makers.flight_log_session import read_log
from groundstation.session_makers.flight_log_session import load_log
from groundstation.estimation import create
from groundstation.estimation.evaluation import inclination_error_rad, score
from groundstation.errors import UserError
from groundstation.units import STANDARD_GRAVITY_M_S2

from mavlink_helpers import BOOT_US, px4_flight, write_ulog

@pytest.fixture(scope="module")
def ulg(tmp_path_factory):
    topics, truth = px4_flight()
    path = tmp_path_factory.mktemp("ulog") / "sim.ulg"
    write_ulog(path, topics, {"sys_name": "PX4"})
    return path, topics, truth


def test_topics_become_project_units_on_the_autopilot_clock(ulg):
    path, topics, truth = ulg
    log = read_log(path)
    assert log.format == "ulog" and log.autopilot == "PX4"
    assert log.imu.source == "sensor_combined" and log.imu.rate_hz == pytest.approx(200.0)
    assert np.array_equal(log.imu.time_us, topics["sensor_combined"][1]["timestamp"].astype(np.int64))
    acc_g = log.imu.stack(["acc_x_g", "acc_y_g", "acc_z_g"])
    assert np.allclose(acc_g, truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2, atol=1e-6)  # float32 in the file
    assert np.allclose(log.imu.stack(["gyr_x_rad_s", "gyr_y_rad_s", "gyr_z_rad_s"]), truth.rate_body_rad_s, atol=1e-6)
    assert log.onboard.source == "vehicle_attitude" and log.truth.source == "vehicle_attitude_groundtruth"
    assert log.gps.columns["satellites"][0] == 11 and log.gps.columns["lat_deg"][0] == pytest.approx(47.0, abs=1e-7)
    assert log.mag is None and log.baro is None


def test_host_filters_against_the_simulator_truth_and_the_onboard_copy(ulg):
    data = load_log(ulg[0], ["hf", "ecf"])
    assert data.true_frame == "NED" and len(data) == 2400
    errors = data.evaluate()
    # The same filters run directly on the simulator's arrays (no file, no reader) score the same, up
    # to the file's float32 rounding: the flight profile's manoeuvres cost them ~6 degrees either way.
    truth = ulg[2]
    for name in ("hf", "ecf"):
        q, _ = create(name).run(truth.rate_body_rad_s, truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2, 1 / 200)
        direct = score(inclination_error_rad(q, truth.q_body_to_ned, "NED"))
        assert errors[name]["incl_rmse_deg"] == pytest.approx(direct["incl_rmse_deg"], abs=0.02)
    assert errors["onboard"]["incl_rmse_deg"] < 0.05  # the onboard copy is the truth, interpolated from 50 Hz
    agree = onboard_agreement(data)
    assert agree["hf"]["rows"] == len(data) - 3  # the last rows lie after the last 50 Hz sample
    # Against the onboard copy of the truth, pitch and roll differences make up the inclination error.
    pitch, roll = agree["hf"]["pitch_rms_deg"], agree["hf"]["roll_rms_deg"]
    assert max(pitch, roll) < errors["hf"]["incl_rmse_deg"] * 1.5 and np.hypot(pitch, roll) > errors["hf"]["incl_rmse_deg"] * 0.7


def test_a_ulog_cut_short_loads_what_it_holds(ulg, tmp_path):
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(ulg[0].read_bytes()[: int(ulg[0].stat().st_size * 0.6)])
    log = read_log(cut)
    assert 0 < len(log.imu) < 2400 and np.all(np.diff(log.imu.time_us) > 0)


def test_not_a_ulog_is_a_clear_error(tmp_path):
    path = tmp_path / "x.ulg"
    path.write_bytes(b"PK\x03\x04 not a log")
    with pytest.raises(UserError, match="not a PX4 ULog"):
        read_log(path)


def test_rows_at_implausible_times_are_dropped_and_said(tmp_path):
    """One flipped bit in the top byte of a timestamp (2^56 µs: the row at 7.2e10 s) is damage: the row
    is dropped, the log says so, and the session's damage list carries it."""
    topics, _ = px4_flight(duration_s=4.0)
    stamps = topics["sensor_combined"][1]["timestamp"]
    stamps[300] = float(int(stamps[300]) ^ (1 << 56))
    path = tmp_path / "damaged.ulg"
    write_ulog(path, topics, {"sys_name": "PX4"})
    log = read_log(path)
    assert len(log.imu) == len(stamps) - 1 and log.imu.time_us.max() == int(stamps[-1])
    said = [d for d in log.damage if "sensor_combined" in d]
    assert len(said) == 1 and "1 row" in said[0] and "7.21e+10 s" in said[0], log.damage
    data = load_log(path, ["hf"])
    assert said[0] in data.damage and (data.time_s < 5.0).all()

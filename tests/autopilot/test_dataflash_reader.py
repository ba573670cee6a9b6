"""ArduPilot DataFlash .bin: a file written here record by record (FMT declarations, then data), read
back through the importer in the project's units; the simulator's truth as ATT checks the Euler order."""

import numpy as np
import pytest

from groundstation import quaternion
from groundstation.session_makers.flight_log_session import read_log
from groundstation.errors import UserError
from groundstation.sim.profiles import make_profile
from groundstation.units import STANDARD_GRAVITY_M_S2

from mavlink_helpers import write_dataflash


@pytest.fixture(scope="module")
def bin_log(tmp_path_factory):
    profile = make_profile("flight", 10.0, seed=6)
    t_s = np.arange(500) / 50.0
    truth = profile.truth(t_s)
    time_us = (20_000_000 + t_s * 1e6).astype(int)
    acc = truth.specific_force_body_m_s2()
    yaw, pitch, roll = np.degrees(quaternion.to_euler_zyx(truth.q_body_to_ned)).T
    imu = [(int(t), i, *truth.rate_body_rad_s[k], *acc[k]) for k, t in enumerate(time_us) for i in (0, 1)]  # two IMUs
    att = [(int(t), r, p, y % 360) for t, r, p, y in zip(time_us[::5], roll[::5], pitch[::5], yaw[::5])]
    mag = [(int(t), 0, 200 + k, -50, 400) for k, t in enumerate(time_us[::5])]
    baro = [(int(t), 0, 101_325.0 - k, 25.0) for k, t in enumerate(time_us[::5])]
    gps = [(int(t), 0, 3, 52.5, 13.4, 40.0, 2.0, 90.0, -0.5, 14) for t in time_us[::10]]
    path = tmp_path_factory.mktemp("df") / "flight.bin"
    write_dataflash(path, {
        "IMU": ("QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ", imu),
        "ATT": ("Qfff", "TimeUS,Roll,Pitch,Yaw", att),
        "MAG": ("QBhhh", "TimeUS,I,MagX,MagY,MagZ", mag),
        "BARO": ("QBff", "TimeUS,I,Press,Temp", baro),
        "GPS": ("QBBdddfffB", "TimeUS,I,Status,Lat,Lng,Alt,Spd,GCrs,VZ,NSats", gps),
    })  # fmt: skip
    return path, truth, time_us


def test_instance_zero_in_project_units(bin_log):
    path, truth, time_us = bin_log
    log = read_log(path)
    assert log.format == "dataflash" and log.imu.source == "IMU[0]" and len(log.imu) == 500  # IMU[1] left out
    assert np.array_equal(log.imu.time_us, time_us)
    acc_g = log.imu.stack(["acc_x_g", "acc_y_g", "acc_z_g"])
    assert np.allclose(acc_g, truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2, atol=1e-6)
    assert log.mag.stack(["mag_x_uT", "mag_y_uT", "mag_z_uT"])[3] == pytest.approx((20.3, -5.0, 40.0))  # mGauss * 0.1
    assert log.baro.columns["pressure_hpa"][0] == pytest.approx(1013.25)
    gps = log.gps.columns
    assert (gps["vel_n_m_s"][0], gps["vel_e_m_s"][0], gps["vel_d_m_s"][0]) == pytest.approx((0.0, 2.0, -0.5), abs=1e-6)


def test_att_degrees_become_the_true_body_to_ned_quaternion(bin_log):
    path, truth, _ = bin_log
    log = read_log(path)
    q_true = truth.q_body_to_ned[::5]
    assert np.degrees(quaternion.angle_between(log.onboard.stack(["qw", "qx", "qy", "qz"]), q_true)).max() < 1e-3


def test_not_a_dataflash_log_is_a_clear_error(tmp_path):
    path = tmp_path / "x.bin"
    path.write_bytes(b"\x7fELF binary, not a log")
    with pytest.raises(UserError, match="not an ArduPilot DataFlash log"):
        read_log(path)

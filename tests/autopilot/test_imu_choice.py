"""The IMU the estimators run on is the first with real samples (varying, about 1 g at rest), whatever
its message: every shared log's ``imu`` table reads about 1 g at rest, as the log's own messages read by
pymavlink / pyulog say (not the project's readers). The choice is said in the session's warnings and
metadata (the Session sheet). Long tlogs are cut to their start to keep each test within seconds."""

import numpy as np
import pytest
from pymavlink import DFReader, mavutil
from pyulog import ULog

from groundstation.session_makers.load import load_session

from mavlink_helpers import flightlog

IMU_MESSAGES = ("RAW_IMU", "SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3", "HIGHRES_IMU")
# file -> bytes kept (None: whole)
LOGS = {
    "ardusub_rov_surface.tlog": 500_000,
    "arduplane_quadplane_sitl.tlog": 400_000,
    "ardurover_boat_sitl_autotest.tlog": 600_000,
    "arducopter_cubeorange_2023-07-06_10-12-18.bin": None,
    "px4_auavx21_bench_sample.ulg": None,
    "px4_fmuv5_quad_hop.ulg": None,
    "px4_sitl_quad_groundtruth.ulg": None,
}


def kept(tmp_path, name):
    size = LOGS[name]
    if size is None:
        return flightlog(name)
    path = tmp_path / name
    path.write_bytes(flightlog(name).read_bytes()[:size])
    return path


def independent_norms_g(path) -> dict[str, float]:
    """Median |acceleration| (g) of each IMU stream of the log, by pymavlink's or pyulog's own reading."""
    samples = {}
    if path.suffix == ".tlog":
        log = mavutil.mavlink_connection(str(path))
        while (msg := log.recv_match(type=list(IMU_MESSAGES))) is not None:
            scale = 1 / 9.80665 if msg.get_type() == "HIGHRES_IMU" else 1e-3  # m/s² or mG
            samples.setdefault(msg.get_type(), []).append(np.array([msg.xacc, msg.yacc, msg.zacc]) * scale)
    elif path.suffix == ".bin":
        log = DFReader.DFReader_binary(str(path))
        while (msg := log.recv_match(type="IMU")) is not None:
            samples.setdefault(f"IMU[{msg.I}]", []).append(np.array([msg.AccX, msg.AccY, msg.AccZ]) / 9.80665)
    else:
        data = ULog(str(path), ["sensor_combined"]).get_dataset("sensor_combined").data
        samples["sensor_combined"] = np.column_stack([data[f"accelerometer_m_s2[{i}]"] for i in range(3)]) / 9.80665
    return {name: float(np.median(np.linalg.norm(np.array(rows), axis=1))) for name, rows in samples.items()}


@pytest.mark.parametrize("name", LOGS)
def test_every_shared_logs_imu_reads_about_1_g_as_its_own_messages_do(tmp_path, name):
    path = kept(tmp_path, name)
    data = load_session(path, filters=())
    acc = np.column_stack([data.tables["imu"][f"acc_{a}_g"] for a in "xyz"])
    ours = float(np.nanmedian(np.linalg.norm(acc, axis=1)))
    theirs = independent_norms_g(path)
    assert ours == pytest.approx(1.0, abs=0.05), (ours, theirs)
    assert any(ours == pytest.approx(norm, abs=0.002) for norm in theirs.values()), (ours, theirs)


def test_ardusub_takes_raw_imu_over_the_empty_scaled_imu2_and_says_so(tmp_path):
    data = load_session(kept(tmp_path, "ardusub_rov_surface.tlog"), filters=())
    said = [w for w in data.warnings if "SCALED_IMU2" in w]
    assert said and "RAW_IMU" in said[0], data.warnings
    assert "RAW_IMU" in data.metadata["imu_choice"] and "SCALED_IMU2" in data.metadata["imu_choice"]

"""A flight log's MCAP is stamped with the log's own UTC time (DataFlash GPS week and ms, ULog
``time_utc_usec``, a ``.tlog``'s receive time), checked against pymavlink's and pyulog's reading of it."""

from datetime import datetime, timezone

import pytest
from mcap.reader import make_reader

from tests.export.conftest import DATASETS

LOGS = DATASETS / "flightlogs"


def first_imu_and_time_metadata(log, exported_log) -> tuple[float, dict]:
    """The log time of the MCAP's first /imu message (s since 1970) and its ``time`` metadata."""
    _, path = exported_log(log.name)
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        stream.seek(0)
        first = next(message.log_time for _, _, message in make_reader(stream).iter_messages(topics=["/imu"]))
    return first / 1e9, metadata.get("time", {})


def need(path):
    if not path.exists():
        pytest.skip(f"{path.name} not found")
    return path


def test_a_dataflash_log_on_its_gps_time(exported_log):
    from pymavlink import DFReader

    log = need(LOGS / "arducopter_cubeorange_2023-07-06_10-12-18.bin")
    stamp_s, time = first_imu_and_time_metadata(log, exported_log)
    reader = DFReader.DFReader_binary(str(log), zero_time_base=False)  # its clock from the first GPS time
    truth = next(m for m in iter(reader.recv_msg, None) if m.get_type() == "IMU" and getattr(m, "I", 0) == 0)._timestamp
    assert abs(stamp_s - truth) < 0.05, (stamp_s, truth)
    assert datetime.fromtimestamp(stamp_s, timezone.utc).date().isoformat() == "2023-07-06"
    assert time["source"] == "GPS week and ms (GWk, GMS)" and time["session_time_0_utc"].startswith("2023-07-06T09:12")


def test_a_ulog_on_its_utc_time(exported_log):
    from pyulog import ULog

    log = need(LOGS / "px4_fmuv5_quad_hop.ulg")
    stamp_s, time = first_imu_and_time_metadata(log, exported_log)
    ulog = ULog(str(log), ["vehicle_gps_position", "sensor_combined"])
    topics = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    gps = topics["vehicle_gps_position"]
    fixed = gps["time_utc_usec"] > 0
    utc_minus_boot_us = gps["time_utc_usec"][fixed] - gps["timestamp"][fixed]  # pyulog's reading of the log
    truth = (topics["sensor_combined"]["timestamp"][0] + utc_minus_boot_us) / 1e6
    assert truth.min() - 0.001 <= stamp_s <= truth.max() + 0.001, (stamp_s, truth)
    assert time["source"] == "vehicle_gps_position.time_utc_usec" and time["session_time_0_utc"].startswith("2023-10-31")


def test_a_tlog_on_its_receive_time(exported_log):
    from pymavlink import mavutil

    log = need(LOGS / "arduplane_quadplane_sitl.tlog")
    stamp_s, time = first_imu_and_time_metadata(log, exported_log)
    connection = mavutil.mavlink_connection(str(log))
    imu = connection.recv_match(type=["HIGHRES_IMU", "RAW_IMU", "SCALED_IMU"])  # its receive time, by pymavlink
    assert abs(stamp_s - imu._timestamp) < 1.0, (stamp_s, imu._timestamp)
    assert time["source"] == ".tlog receive time"


def test_a_log_without_utc_time_says_so(exported_log):
    log = need(LOGS / "px4_sitl_quad_groundtruth.ulg")  # its GPS never had a time (time_utc_usec 0)
    stamp_s, time = first_imu_and_time_metadata(log, exported_log)
    assert 0 <= stamp_s < 86400 and "no UTC time" in time["log_time"] and "source" not in time

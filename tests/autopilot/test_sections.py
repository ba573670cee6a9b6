"""A flyer's sections of a flight log (issue 34): desired against actual attitude and rates, battery, GPS and
actuator outputs, as Mission Planner and Flight Review show them, made as tables of the session with their
units in their names. The oracles are pymavlink (DFReader, mavutil on a tlog) and pyulog reading the same shared
logs, converted here by hand; a session of the project's own aircraft gets no section."""

import math

import numpy as np
import pytest
from pymavlink import DFReader, mavutil
from pyulog import ULog

from groundstation import quaternion
from groundstation.autopilot.sections import SECTIONS
from groundstation.session_makers.load import load_session

from mavlink_helpers import flightlog

COPTER = "arducopter_cubeorange_2023-07-06_10-12-18.bin"
HOP = "px4_fmuv5_quad_hop.ulg"
SUB = "ardusub_rov_surface.tlog"
NAMES = [section.info.name for section in SECTIONS]


@pytest.fixture(scope="module")
def copter():
    return load_session(flightlog(COPTER), filters=("ahf2",))


def dataflash(name: str) -> dict[str, list]:
    """Every message of the given types, by type, as DFReader reads them (its scaling applied)."""
    reader, out = DFReader.DFReader_binary(str(flightlog(name))), {}
    while (msg := reader.recv_match(type=["ATT", "RATE", "BAT", "GPS", "RCOU"])) is not None:
        out.setdefault(msg.get_type(), []).append(msg)
    return out


def session_us(data, table: str) -> np.ndarray:
    """A table's times on the autopilot's clock (µs): its session time from the first IMU row."""
    return data.tables[table]["time_s"] * 1e6 + data.tables["imu"]["device_time_us"][0]


def test_a_dataflash_log_has_every_section_read_as_pymavlink_reads_it(copter):
    assert set(NAMES) <= set(copter.tables) and all(name in copter.catalogue for name in NAMES)
    logged = dataflash(COPTER)
    att, rate, bat, rcou = logged["ATT"], logged["RATE"], logged["BAT"], logged["RCOU"]
    gps = [m for m in logged["GPS"] if m.I == 0]
    for table, messages, pairs in (
        ("attitude_setpoint", att, {"roll_deg": "DesRoll", "pitch_deg": "DesPitch", "yaw_deg": "DesYaw"}),
        ("attitude", att, {"roll_deg": "Roll", "pitch_deg": "Pitch", "yaw_deg": "Yaw"}),
        ("rates_setpoint", rate, {"roll_deg_s": "RDes", "pitch_deg_s": "PDes", "yaw_deg_s": "YDes"}),
        ("rates", rate, {"roll_deg_s": "R", "pitch_deg_s": "P", "yaw_deg_s": "Y"}),
        ("battery", bat, {"voltage_V": "Volt", "current_A": "Curr", "remaining_pct": "RemPct", "used_mAh": "CurrTot"}),
        ("gps_quality", gps, {"fix_type": "Status", "satellites": "NSats", "hdop": "HDop"}),
        ("outputs", rcou, {f"out_{i}_us": f"C{i}" for i in range(1, 15)}),
    ):
        np.testing.assert_allclose(session_us(copter, table), [m.TimeUS for m in messages], atol=0.5, err_msg=table)
        for column, field in pairs.items():
            np.testing.assert_allclose(copter.tables[table][column], [getattr(m, field) for m in messages], rtol=1e-6,
                                       err_msg=f"{table}.{column}")
    assert np.ptp(copter.tables["attitude_setpoint"]["roll_deg"]) > 30  # it flew: roll up to 44°
    units = {c.name: c.unit for c in copter.catalogue["rates"].columns}
    assert units == {"time_s": "s", "roll_deg_s": "deg/s", "pitch_deg_s": "deg/s", "yaw_deg_s": "deg/s"}


def test_a_ulog_has_its_setpoints_rates_battery_gps_and_outputs_in_degrees_as_pyulog_reads_them():
    data = load_session(flightlog(HOP), filters=("ahf2",))
    ulog = ULog(str(flightlog(HOP)))
    topic = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    t0_us = data.tables["imu"]["device_time_us"][0]
    for table, name, pairs, factor in (
        ("attitude_setpoint", "vehicle_attitude_setpoint", {"roll_deg": "roll_body", "pitch_deg": "pitch_body", "yaw_deg": "yaw_body"},
         180.0 / math.pi),
        ("rates_setpoint", "vehicle_rates_setpoint", {"roll_deg_s": "roll", "pitch_deg_s": "pitch", "yaw_deg_s": "yaw"}, 180.0 / math.pi),
        ("rates", "vehicle_angular_velocity", {"roll_deg_s": "xyz[0]", "pitch_deg_s": "xyz[1]", "yaw_deg_s": "xyz[2]"}, 180.0 / math.pi),
        ("battery", "battery_status", {"voltage_V": "voltage_v", "current_A": "current_a", "used_mAh": "discharged_mah"}, 1.0),
        ("gps_quality", "vehicle_gps_position", {"fix_type": "fix_type", "satellites": "satellites_used", "hdop": "hdop"}, 1.0),
        ("outputs", "actuator_outputs", {f"out_{i + 1}_us": f"output[{i}]" for i in range(16)}, 1.0),
    ):
        np.testing.assert_allclose(data.tables[table]["time_s"] * 1e6 + t0_us, topic[name]["timestamp"], atol=0.5, err_msg=table)
        for column, field in pairs.items():
            np.testing.assert_allclose(data.tables[table][column], topic[name][field].astype(float) * factor, rtol=1e-6,
                                       err_msg=f"{table}.{column}")
    np.testing.assert_allclose(data.tables["battery"]["remaining_pct"], topic["battery_status"]["remaining"] * 100.0, rtol=1e-6)
    q = np.column_stack([topic["vehicle_attitude"][f"q[{i}]"] for i in range(4)])  # PX4: w first, body -> NED
    yaw, pitch, roll = np.degrees(quaternion.to_euler_zyx(q)).T
    np.testing.assert_allclose(data.tables["attitude"]["roll_deg"], roll, atol=1e-5)
    np.testing.assert_allclose(data.tables["attitude"]["pitch_deg"], pitch, atol=1e-5)
    assert {c.name for c in data.catalogue["attitude_setpoint"].columns} == {"time_s", "roll_deg", "pitch_deg", "yaw_deg"}


def test_a_tlog_has_the_desired_attitude_battery_gps_and_outputs_as_mavutil_reads_them():
    data = load_session(flightlog(SUB), filters=("ahf2",))
    log = mavutil.mavlink_connection(str(flightlog(SUB)))
    got: dict[str, list] = {}
    while (msg := log.recv_match(type=["NAV_CONTROLLER_OUTPUT", "SYS_STATUS", "SERVO_OUTPUT_RAW", "GPS_RAW_INT"])) is not None:
        if (msg.get_srcSystem(), msg.get_srcComponent()) == (1, 1):  # the autopilot
            got.setdefault(msg.get_type(), []).append(msg)
    nav, sys_status, servo, gps = (got[k] for k in ("NAV_CONTROLLER_OUTPUT", "SYS_STATUS", "SERVO_OUTPUT_RAW", "GPS_RAW_INT"))
    np.testing.assert_allclose(data.tables["attitude_setpoint"]["roll_deg"], [m.nav_roll for m in nav])
    np.testing.assert_allclose(data.tables["attitude_setpoint"]["pitch_deg"], [m.nav_pitch for m in nav])
    assert "yaw_deg" not in data.tables["attitude_setpoint"]  # NAV_CONTROLLER_OUTPUT has none: not made up
    np.testing.assert_allclose(data.tables["battery"]["voltage_V"], [m.voltage_battery / 1000.0 for m in sys_status])
    np.testing.assert_allclose(data.tables["battery"]["current_A"], [m.current_battery / 100.0 for m in sys_status])
    for i in range(1, 9):
        np.testing.assert_allclose(data.tables["outputs"][f"out_{i}_us"], [getattr(m, f"servo{i}_raw") for m in servo])
    np.testing.assert_allclose(data.tables["gps_quality"]["satellites"], [m.satellites_visible for m in gps])
    q = np.column_stack([data.tables["onboard"][f"q{c}"] for c in "wxyz"])
    np.testing.assert_allclose(data.tables["attitude"]["roll_deg"], np.degrees(quaternion.to_euler_zyx(q))[:, 2])


def test_a_session_of_the_projects_own_aircraft_has_no_sections(tmp_path):
    from groundstation.cli import main

    path = tmp_path / "flight.gsrec"
    assert main(["simulate", "--scenario", "flight", "--duration", "3", "--seed", "1", "--out", str(path)]) == 0
    data = load_session(path, filters=("ahf2",))
    assert not set(NAMES) & set(data.tables) and not any(name in data.catalogue for name in NAMES)


def test_a_ulogs_unknown_battery_current_is_no_number():
    """PX4 writes -1 for a current it does not measure (the SITL log): not a battery charging at 1 A."""
    name = "px4_sitl_quad_groundtruth.ulg"
    data = load_session(flightlog(name), filters=("ahf2",))
    battery = next(d.data for d in ULog(str(flightlog(name))).data_list if d.name == "battery_status")
    unknown = battery["current_a"] == -1.0
    assert unknown.any()
    assert np.isnan(data.tables["battery"]["current_A"][unknown]).all()
    np.testing.assert_allclose(data.tables["battery"]["current_A"][~unknown], battery["current_a"][~unknown], rtol=1e-6)


def test_a_tlogs_gps_quality_has_hdop_and_its_unknowns_as_gaps_as_mavutil_reads_them():
    """GPS_RAW_INT.eph is HDOP × 100, UINT16_MAX when unknown (the boat's 132 fixes before its GPS had one, with
    satellites_visible 0 and fix 0); satellites_visible 255 is unknown too. Neither is a number on the plot."""
    name = "ardurover_boat_sitl_autotest.tlog"
    data = load_session(flightlog(name), filters=("ahf2",))
    log = mavutil.mavlink_connection(str(flightlog(name)))
    gps = []
    while (msg := log.recv_match(type="GPS_RAW_INT")) is not None:
        if (msg.get_srcSystem(), msg.get_srcComponent()) == (1, 1):
            gps.append(msg)
    eph = np.array([m.eph for m in gps], dtype=float)
    assert (eph == 65535).sum() > 100 and (eph < 65535).sum() > 1000
    quality = data.tables["gps_quality"]
    gap = np.isnan(quality["fix_type"])  # the gap row the boat's clock jump puts in every table (pipeline.gap_row)
    assert gap.sum() == len(gap) - len(gps)
    quality = {name: values[~gap] for name, values in quality.items()}
    np.testing.assert_allclose(quality["hdop"], np.where(eph == 65535, np.nan, eph / 100.0), equal_nan=True)
    satellites = np.array([m.satellites_visible for m in gps], dtype=float)
    np.testing.assert_allclose(quality["satellites"], np.where(satellites == 255, np.nan, satellites), equal_nan=True)
    np.testing.assert_allclose(quality["fix_type"], [m.fix_type for m in gps])
    assert np.nanmax(quality["hdop"]) < 100  # never 655.35

"""What an autopilot said in its own log (issue 23): DataFlash MSG/ERR/EV/MODE/ARM/PARM and ULog logged
messages, parameters and vehicle_status, read into the session's events and parameters, checked against
pymavlink's DFReader and pyulog as the independent readers, on the shared logs and on logs built here."""

import numpy as np
import pytest
from pymavlink import DFReader
from pyulog import ULog

from groundstation.autopilot.modes import mode_spans
from groundstation.session_makers.load import load_session
from mavlink_helpers import flightlog, write_dataflash

FILTERS = ("ahf2",)
SYSLOG = ("EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG")
# PX4's vehicle_status.nav_state (msg/vehicle_status.msg) by the name QGroundControl and pymavlink give
# the custom mode PX4 sends for it
PX4_MODES = {0: "MANUAL", 1: "ALTCTL", 2: "POSCTL", 3: "MISSION", 4: "LOITER", 5: "RTL", 14: "OFFBOARD", 15: "STABILIZED",
             17: "TAKEOFF", 18: "LAND"}  # fmt: skip


def of_kind(data, kind):
    return [e for e in data.events if e["kind"] == kind]


def dfreader(path, kinds):
    """DFReader's reading: the messages of ``kinds``, and after each MODE the flight mode it names."""
    reader = DFReader.DFReader_binary(str(path), zero_time_base=False)
    out, modes = [], []
    while (msg := reader.recv_match(type=list(kinds))) is not None:
        out.append(msg)
        if msg.get_type() == "MODE":
            modes.append(reader.flightmode)
    return out, modes, reader.params


@pytest.mark.parametrize("name", ["arducopter_cubeorange_2023-07-06_10-12-18.bin", "arduplane_omnibusf4_ground_pilot_0004.bin"])
def test_a_dataflash_logs_texts_modes_and_parameters(name):
    path = flightlog(name)
    data = load_session(path, filters=FILTERS)
    logged, modes, params = dfreader(path, ["MSG", "EV", "MODE", "PARM", "ARM"])
    texts = [m.Message for m in logged if m.get_type() == "MSG"]
    assert texts and [e["message"] for e in of_kind(data, "message") if e["source"] == "MSG"] == texts
    assert len([e for e in of_kind(data, "message") if e["source"] == "EV"]) == len([m for m in logged if m.get_type() == "EV"])
    assert data.parameters == params  # DFReader's own table of the PARM messages, each name's last value
    changes, last = [], {}
    for m in logged:
        if m.get_type() == "PARM":
            if m.Name in last and last[m.Name] != m.Value:
                changes.append((m.Name, m.Value))
            last[m.Name] = m.Value
    assert [(e["name"], e["value"]) for e in of_kind(data, "parameter")] == changes
    status = of_kind(data, "vehicle_status")
    assert list(dict.fromkeys(e["mode"] for e in status)) == list(dict.fromkeys(modes))
    t0_us = data.tables["imu"]["device_time_us"][0] if len(data.tables["imu"]["time_s"]) else None
    if t0_us is not None:  # the mode's time on the session's axis: the MODE message's TimeUS
        mode_us = [m.TimeUS for m in logged if m.get_type() == "MODE"]
        assert status[0]["t_s"] == pytest.approx((mode_us[0] - t0_us) / 1e6, abs=1e-6)


def test_the_copter_flew_armed_in_loiter_then_rtl_and_disarmed_at_the_end():
    """The README's flight: LOITER then RTL; the log began armed (its first word on arming is the disarm)."""
    data = load_session(flightlog("arducopter_cubeorange_2023-07-06_10-12-18.bin"), filters=FILTERS)
    logged, _, _ = dfreader(flightlog("arducopter_cubeorange_2023-07-06_10-12-18.bin"), ["EV", "ARM"])
    disarm_us = min(m.TimeUS for m in logged if (m.get_type(), getattr(m, "Id", None)) == ("EV", 11) or m.get_type() == "ARM")
    spans = mode_spans(data.events, float(data.time_s[-1]))
    assert [(s.mode, s.armed) for s in spans] == [("LOITER", True), ("RTL", True), ("RTL", False)]
    assert spans[2].start_s == pytest.approx((disarm_us - data.tables["imu"]["device_time_us"][0]) / 1e6, abs=1e-6)


@pytest.mark.parametrize("name", ["px4_auavx21_bench_sample.ulg", "px4_fmuv5_quad_hop.ulg", "px4_sitl_quad_groundtruth.ulg"])
def test_a_ulogs_messages_parameters_and_modes(name):
    path = flightlog(name)
    data = load_session(path, filters=FILTERS)
    ulog = ULog(str(path), ["vehicle_status"])
    said = [(SYSLOG[int(m.log_level) - ord("0")], m.message) for m in ulog.logged_messages]
    assert [(e["severity"], e["message"]) for e in of_kind(data, "message")] == said
    params = {k: float(v) for k, v in ulog.initial_parameters.items()}
    for _, key, value in ulog.changed_parameters:
        params[key] = float(value)
    assert data.parameters == params
    status = ulog.get_dataset("vehicle_status").data
    states = [(PX4_MODES[int(n)], int(a) == 2) for n, a in zip(status["nav_state"], status["arming_state"])]
    changes = [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]]
    assert [(e["mode"], e["armed"]) for e in of_kind(data, "vehicle_status")] == changes


def test_the_sitl_mission_armed_took_off_loitered_and_returned():
    data = load_session(flightlog("px4_sitl_quad_groundtruth.ulg"), filters=FILTERS)
    spans = mode_spans(data.events, float(data.time_s[-1]))
    assert [s.mode for s in spans if s.armed] == ["LOITER", "TAKEOFF", "LOITER", "RTL"]
    assert np.all(np.diff([s.start_s for s in spans]) > 0)


def test_a_built_dataflash_log_says_errors_events_and_arming(tmp_path):
    """A log made here: a plane (its firmware message names the vehicle type) in FBWA (5 on a plane, LOITER
    on a copter), armed by EV 10, a radio failsafe (ERR 5/1) resolved, then disarmed by ARM 0."""
    path = tmp_path / "plane.bin"
    write_dataflash(path, {
        "MSG": ("QZ", "TimeUS,Message", [(1_000_000, b"ArduPlane V4.5.0 (abcdef12)")]),
        "PARM": ("QNf", "TimeUS,Name,Value", [(1_000_100, b"THR_MAX", 100.0), (3_000_000, b"THR_MAX", 80.0)]),
        "MODE": ("QBBB", "TimeUS,Mode,ModeNum,Rsn", [(1_500_000, 5, 5, 1)]),
        "EV": ("QB", "TimeUS,Id", [(2_000_000, 10)]),
        "ERR": ("QBB", "TimeUS,Subsys,ECode", [(2_500_000, 5, 1), (2_600_000, 5, 0)]),
        "ARM": ("QB", "TimeUS,ArmState", [(4_000_000, 0)]),
        "ATT": ("Qfff", "TimeUS,Roll,Pitch,Yaw", [(1_000_000 + 40_000 * i, 0.0, 0.0, 90.0) for i in range(100)]),
    })  # fmt: skip
    data = load_session(path, filters=FILTERS)
    said = [(e["source"], e["message"], e["severity"]) for e in of_kind(data, "message")]
    assert said == [("MSG", "ArduPlane V4.5.0 (abcdef12)", None), ("EV", "ARMED", None),
                    ("ERR", "FAILSAFE_RADIO: error 1", "ERROR"), ("ERR", "FAILSAFE_RADIO: resolved", "INFO")]
    assert [(e["mode"], e["armed"]) for e in of_kind(data, "vehicle_status")] == [("FBWA", False), ("FBWA", True), ("FBWA", False)]
    assert data.parameters == {"THR_MAX": 80.0}
    assert [(e["name"], e["previous"], e["value"], e["t_s"]) for e in of_kind(data, "parameter")] == [("THR_MAX", 100.0, 80.0, 2.0)]

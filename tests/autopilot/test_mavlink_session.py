"""A live MAVLink stream through the session machinery the app uses: ``open_session(spec)`` on the
simulated ArduPilot-like aircraft over a real pseudo-terminal and over real UDP on localhost, shown
(the pipeline's tables), recorded (the session's recording) and replayed (``load_session``); values
against the simulator's truth."""

import argparse
import dataclasses
import math
import os
import re
import subprocess
import sys
import time

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation import quaternion
from groundstation.autopilot.decoder import new_parser
from groundstation.autopilot.imu_rate import slow_imu_note
from groundstation.commands.bridge_sim import add_arguments
from groundstation.estimation.evaluation import inclination_error_rad
from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.session_makers.factory import open_session
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sim.mavlink_aircraft import ACC_NOISE_G, GYR_NOISE_RAD_S, MavlinkAircraft
from groundstation.sim.options import scenario_from_args
from groundstation.sim.stream import Scenario
from groundstation.units import STANDARD_GRAVITY_M_S2
from mavlink_helpers import Sender, ardupilot_heartbeat, pty_session
from tests.waiting import wait_for

SCENARIO = dataclasses.replace(Scenario(), profile="flight", duration_s=60.0, seed=3)
FILTERS = ("ahf", "hf")
REQUESTED_PERIOD_US = 20_000  # StreamRequester's 50 Hz


def check_live_tables(session, profile):
    """The imu table at the requested rate with the simulator's values, the onboard attitude, the aiding
    and status tables, and the link counters; returns the imu table as columns."""
    p = session.pipeline
    imu = p.imu.to_dict()
    device_s = imu["device_time_us"] / 1e6
    periods = np.diff(imu["device_time_us"])
    # The requests go up on the first HEARTBEAT; a session that opens on a running link may hear a 4 Hz
    # RAW_IMU or two before it (seen 1 time in 4): from the first requested period on, 50 Hz throughout.
    requested = np.flatnonzero(periods == REQUESTED_PERIOD_US)[0]
    assert len(periods) > 100 and requested <= 2 and np.all(periods[requested:] == REQUESTED_PERIOD_US)
    # Session time is the autopilot's own (no reboot in between): dt is exact.
    assert imu["time_s"][0] >= 0 and np.allclose(imu["time_s"] - imu["time_s"][0], device_s - device_s[0], atol=1e-9)
    truth = profile.truth(device_s)
    acc = np.column_stack([imu[f"acc_{a}_g"] for a in "xyz"])
    gyr = np.column_stack([imu[f"gyr_{a}_rad_s"] for a in "xyz"])
    # White noise and rounding to 1 mG / 1 mrad/s: within 5 sigma + half a count.
    assert np.abs(acc - truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2).max() < 5 * ACC_NOISE_G + 0.0005
    assert np.abs(gyr - truth.rate_body_rad_s).max() < 5 * GYR_NOISE_RAD_S + 0.0005
    # The same estimators as a project-protocol session: HF's attitude follows the truth within 2° in the
    # last second (0.4° measured; AHF converges more slowly from its start: 3.7° after 1.5 s).
    late = device_s > device_s[-1] - 1.0
    q = np.column_stack([imu[f"hf_q{c}"] for c in "wxyz"])
    assert np.degrees(inclination_error_rad(q[late], truth.q_body_to_ned[late], "NED")).max() < 2.0
    assert np.isfinite(imu["ahf_qw"]).all()
    board = p.onboard.to_dict()
    assert len(board["time_s"]) > 50
    q_board = np.column_stack([board[f"q{c}"] for c in "wxyz"])
    q_true = profile.truth(board["device_time_us"] / 1e6).q_body_to_ned
    assert np.degrees(quaternion.angle_between(q_board, q_true)).max() < 1e-3  # ATTITUDE is the truth in float32
    baro = p.tables["baro"].to_dict()
    assert len(baro["time_s"]) >= 10 and 90_000 < np.median(baro["pressure_Pa"]) < 110_000
    assert len(p.tables["gps"]) >= 5 and len(p.tables["heartbeat"]) >= 1 and len(p.tables["sys_status"]) >= 1
    assert p.tables["radio_status"].to_dict()["rssi"].size >= 1  # the SiK radio, system 51
    assert p.decoder.stats.frames > 300 and p.decoder.stats.frames_lost == 0 and p.decoder.stats.bytes_skipped == 0
    assert p.link.per_second.to_dict()["frames"].sum() > 0
    return imu


def check_replay(session, live_imu):
    """The recording says MAVLink and replays to the same imu and onboard rows, estimates included."""
    path = session.recording_path
    assert open_recording(path).metadata["protocol"] == "mavlink"
    data = load_session(path, exact=True)  # the estimators' columns as the live pipeline computed them
    for name, column in live_imu.items():
        np.testing.assert_array_equal(data.tables["imu"][name][: len(column)], column, err_msg=name)
    np.testing.assert_array_equal(data.tables["onboard"]["qw"][: len(session.pipeline.onboard)],
                                  session.pipeline.onboard.to_dict()["qw"])  # fmt: skip
    assert "heartbeat" in data.catalogue and data.catalogue["sys_status"].column("voltage_V").unit == "V"


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")
def test_pty_session_shows_records_and_replays(tmp_path):
    aircraft = MavlinkAircraft(SCENARIO)
    session = pty_session(aircraft, 3.5, filters=FILTERS, recordings_dir=tmp_path)
    assert session.pipeline.protocol == "mavlink"
    assert ("RAW_IMU", 0.02) in aircraft.requests and ("ATTITUDE", 0.02) in aircraft.requests
    assert aircraft.refused == []  # only stream requests went up
    assert session.send_command("calibrate_gyro") == -1  # an autopilot never gets this project's commands
    assert "not sent" in session.pipeline.events[-1]["message"]
    check_replay(session, check_live_tables(session, aircraft.profile))


def test_udp_session_from_the_bridge_sim_process(tmp_path):
    session = open_session("mavlink:udpin:127.0.0.1:0", filters=FILTERS, recordings_dir=tmp_path)
    port = session.source.transport.local_address[1]
    argv = ["--udp", f"127.0.0.1:{port}", "--duration", "4", "--seed", "2"]
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", *argv],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        with session:  # until the process has sent its 4 s and the session has read every byte, however slow the machine
            _, err = process.communicate(timeout=120)
            sent = re.search(r"datagrams, (\d+) bytes", err)
            assert sent, err
            wait_for(lambda: session.pipeline.decoder.stats.bytes_in >= int(sent[1]), what="every datagram read")
    finally:
        process.kill()
    assert process.returncode == 0 and "refused commands []" in err
    assert session.pipeline.decoder.stats.bytes_in == int(sent[1])
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    args = parser.parse_args(argv)
    profile = MavlinkAircraft(scenario_from_args(args, args.duration)).profile  # the process's truth
    check_replay(session, check_live_tables(session, profile))


def test_slow_imu_is_asked_again_and_warned_and_a_reboot_restarts_like_the_projects_aircraft():
    """Bytes from pymavlink's encoder straight into the pipeline: an autopilot that ignores the
    requests keeps its 4 Hz IMU; reboots (its clock starts over)."""
    autopilot = Sender()
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    uplink = []
    t_host_ns = 1_000_000_000
    for i in range(40):  # 10 s at 4 Hz, a heartbeat each second
        time_us = 5_000_000 + i * 250_000 if i < 30 else (i - 30) * 250_000 + 100_000  # reboot at i = 30
        data = ardupilot_heartbeat(autopilot) if i % 4 == 0 else b""
        data += autopilot.raw_imu(time_us, 0, 0, -1000, 0, 0, 0, 200, 0, 400, 0, 2500)
        t_host_ns += 250_000_000
        pipeline.feed(t_host_ns, data)
        uplink.append(pipeline.take_uplink())
    # Stream requests (and nothing else) on the first heartbeat, again every 5 s while the IMU stays slow.
    asked = [i for i, u in enumerate(uplink) if u]
    assert asked == [0, 20]
    parser = new_parser()
    sent = [m for u in uplink for m in parser.parse_buffer(u) or ()]
    assert {m.get_type() for m in sent} == {"REQUEST_DATA_STREAM", "COMMAND_LONG"}
    assert {m.command for m in sent if m.get_type() == "COMMAND_LONG"} == {mavlink.MAV_CMD_SET_MESSAGE_INTERVAL}
    warnings = [e for e in pipeline.events if e["kind"] == "warning"]
    assert [w["message"] for w in warnings] == [slow_imu_note(4.0)]
    assert warnings[0]["t_host_ns"] - 1_250_000_000 >= 5e9  # after the retry had its chance
    resets = [e for e in pipeline.events if e["kind"] == "device_reset"]
    assert len(resets) == 1 and resets[0]["device_time_us_after"] == 100_000
    imu = pipeline.imu.to_dict()
    assert np.all(np.diff(imu["time_s"]) > 0)  # one monotonic axis across the reboot
    assert math.isnan(imu["acc_x_g"][30])  # the gap row every table gets at a restart
    assert imu["acc_z_g"][0] == pytest.approx(-1.0) and imu["gyr_y_rad_s"][0] == 0.0


def test_a_session_that_sped_up_names_one_imu_rate_in_its_warnings_and_its_figures():
    """Issue 34, the tour's defect 3: RAW_IMU at 2 Hz for 10 s, then (the request answered) at 4 Hz for 20 s.
    The live warning said 2.0 Hz when it was made; the session's product says the one rate its figures give
    (the median interval of the whole IMU table: 0.25 s, 4 Hz), once."""
    from groundstation.session_makers.load import pipeline_product

    autopilot = Sender()
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    times_us = [1_000_000 + i * 500_000 for i in range(20)] + [11_000_000 + i * 250_000 for i in range(80)]
    for i, time_us in enumerate(times_us):
        data = ardupilot_heartbeat(autopilot) if i % 4 == 0 else b""
        pipeline.feed(time_us * 1000, data + autopilot.raw_imu(time_us, 0, 0, -1000, 0, 0, 0, 200, 0, 400, 0, 2500))
    live = [e["message"] for e in pipeline.events if e["kind"] == "warning"]
    assert live == [slow_imu_note(2.0)]  # what the window said at the time
    data = pipeline_product({"protocol": "mavlink"}, pipeline, [])
    median_interval_s = float(np.median(np.diff(times_us))) / 1e6
    assert data.imu_rate_hz() == pytest.approx(1.0 / median_interval_s)
    slow = [w for w in data.warnings if "too slow" in w]
    assert slow == [slow_imu_note(data.imu_rate_hz())]
    from groundstation.export.report import events_section

    assert "IMU at 2.0 Hz" not in events_section(data)  # the report's events table does not say it again

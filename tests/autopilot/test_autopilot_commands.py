"""The commands on autopilot files, in process (``cli.main``) on files made here: evaluate reports
agreement with the onboard estimate when there is no truth, export writes every format with the
onboard columns and the agreement table, import saves a recorded MAVLink session as a .tlog."""

import json

import numpy as np
import openpyxl
import pandas as pd
import pytest
from pymavlink import mavutil

from groundstation.autopilot.agreement import onboard_agreement
from groundstation.session_makers.flight_log_session import load_log
from groundstation.session_makers.load import load_session
from groundstation.session.product import exact_estimates
from groundstation.cli import main
from groundstation.recording import RecordingWriter
from groundstation.sim.mavlink_aircraft import MavlinkAircraft

from mavlink_helpers import px4_flight, write_ulog


@pytest.fixture(scope="module")
def px4_log(tmp_path_factory):
    """A PX4-like log without ground truth: the onboard estimate is all there is to compare with."""
    topics, _ = px4_flight(duration_s=5.0)
    del topics["vehicle_attitude_groundtruth"]
    path = tmp_path_factory.mktemp("px4") / "flight.ulg"
    write_ulog(path, topics, {"sys_name": "PX4"})
    return path


def test_evaluate_without_truth_reports_agreement_labelled_as_such(px4_log, capsys):
    assert main(["evaluate", str(px4_log), "--filters", "hf,ecf"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("agreement with the onboard estimate") and "not error" in text and "incl RMSE" not in text
    assert main(["evaluate", str(px4_log), "--filters", "hf,ecf", "--json"]) == 0
    reported = json.loads(capsys.readouterr().out)["agreement_with_onboard"]
    with exact_estimates():  # as evaluate loads it
        data = load_log(px4_log, ["hf", "ecf"])
    assert reported == onboard_agreement(data)
    hf = reported["hf"]
    assert f"{hf['pitch_rms_deg']:.3f}" in text and f"{hf['roll_max_deg']:.3f}" in text


def test_evaluate_on_a_log_without_imu_says_why(tmp_path, capsys):
    topics, _ = px4_flight(duration_s=3.0)
    path = tmp_path / "attitude_only.ulg"
    write_ulog(path, {"vehicle_attitude": topics["vehicle_attitude"]})
    assert main(["evaluate", str(path)]) == 2
    assert "no IMU samples" in capsys.readouterr().err


def test_export_every_format_with_onboard_columns_and_the_agreement_sheet(px4_log, tmp_path, capsys):
    for suffix in ("csv", "parquet", "xlsx"):
        assert main(["export", str(px4_log), "--out", str(tmp_path / f"out.{suffix}"), "--filters", "ahf,hf"]) == 0
    capsys.readouterr()
    csv = pd.read_csv(tmp_path / "out.csv")
    parquet = pd.read_parquet(tmp_path / "out.parquet")
    assert len(csv) == len(parquet) == 1000
    assert {"time_s", "ahf_pitch_deg", "hf_roll_deg", "onboard_pitch_deg", "acc_z_g", "gyr_x_dps", "gps_lat_deg"} <= set(csv.columns)
    assert np.allclose(csv.time_s, parquet.time_s) and csv.time_s.iloc[-1] == pytest.approx(4.995)
    session = [row for row in openpyxl.load_workbook(tmp_path / "out.xlsx")["Session"].iter_rows(values_only=True)]
    title = next(i for i, row in enumerate(session) if row[0] and str(row[0]).startswith("Agreement with the onboard estimate"))
    assert "not an error" in session[title][0]
    data = load_log(px4_log, ["ahf", "hf"])
    expected = onboard_agreement(data)
    rows = {row[0]: row[1:5] for row in session[title + 2 : title + 4]}
    for name in ("ahf", "hf"):
        e = expected[name]
        assert rows[name] == pytest.approx((e["pitch_rms_deg"], e["pitch_max_deg"], e["roll_rms_deg"], e["roll_max_deg"]))
    assert ("autopilot", "PX4") in [row[:2] for row in session]


def test_import_saves_a_recorded_mavlink_session_as_a_tlog(tmp_path, capsys):
    aircraft = MavlinkAircraft()
    chunks = aircraft.advance(3.0)
    recording = tmp_path / "live.gsrec"
    header = {"source": "mavlink:udpin:0.0.0.0:14550", "protocol": "mavlink"}  # as LiveSession records it
    with RecordingWriter(recording, header) as writer:
        for i, chunk in enumerate(chunks):
            writer.write_chunk(10_000_000_000 + int(chunk.t_s * 1e9), chunk.data)
    out = tmp_path / "live.tlog"
    assert main(["import", str(recording), "--out", str(out)]) == 0
    sent = [bytes(m.get_msgbuf()) for c in chunks for m in mavutil.mavlink.MAVLink(None).parse_buffer(c.data) or ()]
    log = mavutil.mavlogfile(str(out))
    saved, stamps = [], []
    while (msg := log.recv_msg()) is not None:
        saved.append(bytes(msg.get_msgbuf()))
        stamps.append(msg._timestamp)
    assert saved == sent and len(saved) > 30
    assert np.all(np.diff(stamps) >= 0) and stamps[-1] - stamps[0] == pytest.approx(chunks[-1].t_s - chunks[0].t_s, abs=1e-3)
    assert f"{len(sent)} MAVLink packets" in capsys.readouterr().out
    assert main(["import", str(recording), "--out", str(out)]) == 2  # exists: never overwritten


def test_import_of_a_flight_log_explains_that_none_is_needed(px4_log, tmp_path, capsys):
    assert main(["import", str(px4_log), "--out", str(tmp_path / "x.gsrec")]) == 2
    assert "no import needed" in capsys.readouterr().err


def test_every_other_tlog_message_is_a_catalogued_table_and_exported(tmp_path, capsys):
    from mavlink_helpers import Sender, ardupilot_heartbeat
    from groundstation.autopilot.tlog import write_tlog

    ap, t0_us = Sender(), 1_700_000_000_000_000
    packets = [(t0_us, ardupilot_heartbeat(ap))]
    for i in range(100):  # IMU at 50 Hz, VFR_HUD at 5 Hz (no time field: placed by its receive time)
        packets.append((t0_us + i * 20_000, ap.raw_imu(3_000_000 + i * 20_000, 0, 0, -1000, 0, 0, 0, 1, 2, 3)))
        if i % 10 == 5:
            packets.append((t0_us + i * 20_000 + 1, ap.vfr_hud(10.0 + i, 11.0, 90, 42, 100.0, 0.5)))
    path = tmp_path / "hud.tlog"
    write_tlog(path, packets)
    data = load_session(path, ["hf"])
    info = data.catalogue["vfr_hud"]
    assert info.column("airspeed_m_s").unit == "m/s" and info.column("throttle_pct").unit == "%"
    assert list(data.tables["vfr_hud"]["airspeed_m_s"]) == [10.0 + i for i in range(5, 100, 10)]
    assert main(["export", str(path), "--out", str(tmp_path / "hud.csv"), "--filters", "hf"]) == 0
    capsys.readouterr()
    csv = pd.read_csv(tmp_path / "hud.csv")
    hud = csv.dropna(subset=["vfr_hud_airspeed_m_s"])
    # Each reading at the session time it arrived at, as live: the autopilot time of the IMU sample before it.
    assert list(hud.vfr_hud_airspeed_m_s) == [10.0 + i for i in range(5, 100, 10)]
    assert np.allclose(hud.time_s, [i * 20_000 / 1e6 for i in range(5, 100, 10)], atol=1e-6)

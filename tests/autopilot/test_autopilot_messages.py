"""What an autopilot says on MAVLink (issue 23): STATUSTEXT texts as ``message`` events, PARAM_VALUE into
``SessionData.parameters`` (changes as events), HEARTBEAT's mode by name and its ``custom_mode`` column,
on the shared .tlogs against pymavlink's own reader (``mavutil``), on .tlogs built here with pymavlink's
encoder, and live from the simulated aircraft through a real pty, whose .tlog gives the same events."""

import dataclasses
import os
import struct

import numpy as np
import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.messages import StatusTexts
from groundstation.autopilot.modes import mode_spans
from groundstation.autopilot.records import StatusText
from groundstation.session_makers.load import load_session
from groundstation.sim.mavlink_aircraft import MavlinkAircraft
from groundstation.sim.stream import Scenario
from mavlink_helpers import Sender, flightlog, pty_session
from tests.cli_in_process import run_in_process

VEHICLE = (1, 1)
SEVERITY = ("EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG")  # MAVLink's MAV_SEVERITY
FILTERS = ("ahf2",)


def vehicle_messages(path, kinds):
    """pymavlink's reading of the .tlog: the vehicle's messages of ``kinds`` in file order."""
    log = mavutil.mavlink_connection(str(path))
    out = []
    while (msg := log.recv_match(type=list(kinds))) is not None:
        if (msg.get_srcSystem(), msg.get_srcComponent()) == VEHICLE:
            out.append(msg)
    return out


def of_kind(data, kind):
    return [e for e in data.events if e["kind"] == kind]


@pytest.mark.parametrize("name", ["arduplane_quadplane_sitl.tlog", "ardusub_rov_surface.tlog"])
def test_statustexts_of_a_tlog_are_events_with_their_text_and_severity(name):
    path = flightlog(name)
    data = load_session(path, filters=FILTERS)
    said = [(SEVERITY[m.severity], m.text) for m in vehicle_messages(path, ["STATUSTEXT"])]
    assert said, "the log has texts from the vehicle"
    events = of_kind(data, "message")
    assert [(e["severity"], e["message"]) for e in events] == said
    assert {e["source"] for e in events} == {"STATUSTEXT"}
    assert all(np.diff([e["t_s"] for e in events]) >= 0)


def test_the_test_drivers_chatter_is_not_the_vehicles():
    """The rover autotest's driver (system 250) says 2,000 texts (chunked) on the link: none is the vehicle's."""
    path = flightlog("ardurover_boat_sitl_autotest.tlog")
    data = load_session(path, filters=FILTERS)
    said = [(SEVERITY[m.severity], m.text) for m in vehicle_messages(path, ["STATUSTEXT"])]
    assert [(e["severity"], e["message"]) for e in of_kind(data, "message")] == said
    assert not any(text.startswith("AT-") for _, text in said)


@pytest.mark.parametrize("name", ["arduplane_quadplane_sitl.tlog", "ardusub_rov_surface.tlog"])
def test_parameters_of_a_tlog_are_the_last_values_sent_and_changes_are_events(name):
    path = flightlog(name)
    data = load_session(path, filters=FILTERS)
    last, changes = {}, []
    for m in vehicle_messages(path, ["PARAM_VALUE"]):
        if m.param_id in last and last[m.param_id] != m.param_value:
            changes.append((m.param_id, last[m.param_id], m.param_value))
        last[m.param_id] = m.param_value
    assert len(last) > 800
    assert data.parameters == last
    assert [(e["name"], e["previous"], e["value"]) for e in of_kind(data, "parameter")] == changes


def test_heartbeat_has_custom_mode_and_modes_are_named_per_vehicle_type():
    path = flightlog("arduplane_quadplane_sitl.tlog")
    data = load_session(path, filters=FILTERS)
    beats = vehicle_messages(path, ["HEARTBEAT"])
    heartbeat = data.tables["heartbeat"]["custom_mode"]
    assert sorted(set(heartbeat[np.isfinite(heartbeat)])) == sorted({m.custom_mode for m in beats})
    names = mavutil.mode_mapping_bynumber(beats[0].type)  # ArduPlane's table: QuadPlane modes included
    expected = []
    for m in beats:
        state = (names[m.custom_mode], bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED))
        if not expected or expected[-1] != state:
            expected.append(state)
    assert [(e["mode"], e["armed"]) for e in of_kind(data, "vehicle_status")] == expected
    spans = mode_spans(data.events, float(data.time_s[-1]))
    assert [(s.mode, s.armed) for s in spans] == expected
    assert spans[-1].end_s == data.time_s[-1]
    assert all(a.end_s == b.start_s for a, b in zip(spans, spans[1:]))


def write_tlog(path, packets):
    """The .tlog layout: each packet after its receive time, µs since 1970 as 8 big-endian bytes."""
    t0_us = 1_700_000_000_000_000
    path.write_bytes(b"".join(struct.pack(">Q", t0_us + 20_000 * i) + p for i, p in enumerate(packets)))


def test_px4_integer_parameters_are_read_from_their_bytes_and_long_texts_are_joined(tmp_path):
    """PX4 copies an INT32 parameter's bytes into PARAM_VALUE's float; a MAVLink 2 text over 50 characters
    comes in chunks sharing an id, the last one shorter (its NUL)."""
    px4 = Sender(1, 1)
    beat = px4.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                         (4 << 16) | (4 << 24), mavlink.MAV_STATE_STANDBY)  # AUTO / MISSION
    as_float = struct.unpack("<f", struct.pack("<i", 1000))[0]  # 1000's bytes read as a float: 1.4e-42
    text = "Preflight Fail: Accel Sensor 0 missing; check the wiring and the calibration"
    chunks = [text[:50], text[50:]]
    packets = [beat, px4.param_value(b"COM_RC_LOSS_T", 0.5, mavlink.MAV_PARAM_TYPE_REAL32, 2, 0),
               px4.param_value(b"MAV_SYS_ID", as_float, mavlink.MAV_PARAM_TYPE_INT32, 2, 1),
               *(px4.statustext(mavlink.MAV_SEVERITY_CRITICAL, c.encode(), 7, i) for i, c in enumerate(chunks)),
               px4.statustext(mavlink.MAV_SEVERITY_INFO, b"Takeoff detected", 0, 0), beat]
    path = tmp_path / "px4.tlog"
    write_tlog(path, packets)
    data = load_session(path, filters=FILTERS)
    assert data.parameters == {"COM_RC_LOSS_T": 0.5, "MAV_SYS_ID": 1000.0}
    assert [(e["severity"], e["message"]) for e in of_kind(data, "message")] == [("CRITICAL", text), ("INFO", "Takeoff detected")]
    assert [e["mode"] for e in of_kind(data, "vehicle_status")] == [mavutil.interpret_px4_mode(0, (4 << 16) | (4 << 24))]


def test_a_text_whose_last_chunk_never_came_is_said_as_far_as_it_got():
    """Chunks lost on the radio: the next text of the sender ends the broken one, said as far as it got."""
    first = "A" * 50
    joined = StatusTexts()
    said = [joined.add(StatusText(1, 1, 0, 4, text, text_id, seq))
            for text_id, seq, text in ((3, 0, first), (4, 0, "B" * 50), (4, 1, "end"), (0, 0, "whole"))]  # fmt: skip
    assert said == [[], [(4, first)], [(4, "B" * 50 + "end")], [(4, "whole")]]


TEXTS = ((0.3, mavlink.MAV_SEVERITY_INFO, "ArduCopter V4.5.7 (simulated)"),
         (0.6, mavlink.MAV_SEVERITY_CRITICAL, "PreArm: Compass not calibrated; Gyros inconsistent by 6 deg/s; check the IMUs"),
         (0.9, mavlink.MAV_SEVERITY_WARNING, "x" * 100))  # exactly two chunks: an empty third ends it  # fmt: skip


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")
def test_a_live_session_says_the_aircrafts_texts_and_its_tlog_says_the_same(tmp_path, capsys):
    aircraft = MavlinkAircraft(dataclasses.replace(Scenario(), profile="static", duration_s=60.0, seed=2), texts=TEXTS)
    session = pty_session(aircraft, 2.5, filters=FILTERS, recordings_dir=tmp_path)
    live = [(e["severity"], e["message"]) for e in session.view.events if e["kind"] == "message"]
    assert live == [(SEVERITY[s], text) for _, s, text in TEXTS]
    tlog = tmp_path / "x.tlog"
    done = run_in_process(capsys, "import", session.recording_path, "--out", tlog)
    assert done.returncode == 0, done.stderr
    recorded, logged = load_session(session.recording_path, filters=FILTERS), load_session(tlog, filters=FILTERS)
    keys = ("kind", "message", "severity", "source", "mode", "armed")
    events = [[{k: e[k] for k in keys if k in e} for e in d.events if e["kind"] in ("message", "vehicle_status")] for d in (recorded, logged)]
    assert events[0] == events[1]
    assert [(e["severity"], e["message"]) for e in events[0] if e["kind"] == "message"] == live

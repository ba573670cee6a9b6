"""Spoofed MAVLink senders inside an accepted stream (a serial or TCP link, or the locked UDP sender):
pymavlink's own encoder makes the bytes, fed straight into the pipeline. The vehicle is the one the
user picked or the first autopilot heard; nobody else replaces it, restarts its estimators, flips its
arming, inflates its losses, receives its stream requests or grows the session without bound."""

from __future__ import annotations

import random

import numpy as np

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.decoder import new_parser
from groundstation.session_makers.pipeline import Pipeline
from groundstation.sources.base import SourceError
from groundstation.sources.spec import open_source
from mavlink_helpers import Sender, ardupilot_heartbeat

SECOND_NS = 1_000_000_000
DISARMED = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED


def imu(sender: Sender, time_us: int) -> bytes:
    return sender.raw_imu(time_us, 0, 0, -1000, 0, 0, 0, 200, 0, 400, 0, 2500)


def fly(pipeline: Pipeline, vehicle: Sender, seconds: int, spoof=lambda i: b"", hz: int = 50, start_ns: int = SECOND_NS) -> list[bytes]:
    """``seconds`` of the vehicle at ``hz`` (a heartbeat each second), ``spoof(i)``'s bytes after each of its
    messages; the uplink taken after every chunk."""
    uplink = []
    for i in range(seconds * hz):
        data = ardupilot_heartbeat(vehicle) if i % hz == 0 else b""
        data += imu(vehicle, 5_000_000 + i * 1_000_000 // hz)
        pipeline.feed(start_ns + i * SECOND_NS // hz, data + spoof(i))
        uplink.append(pipeline.take_uplink())
    return uplink


def targets(uplink: list[bytes]) -> set[int]:
    parser = new_parser()
    return {m.target_system for u in uplink for m in parser.parse_buffer(u) or ()}


def kinds(pipeline: Pipeline, kind: str) -> list[dict]:
    return [e for e in pipeline.events if e["kind"] == kind]


def test_a_picked_vehicle_is_not_taken_over_by_an_earlier_autopilot_and_only_it_gets_requests():
    pipeline = Pipeline(("ahf",), protocol="mavlink", vehicle_system=1)
    intruder = Sender(system=99)
    for i in range(3):  # three ArduPilot heartbeats before the vehicle's first
        pipeline.feed(SECOND_NS + i, ardupilot_heartbeat(intruder))
    uplink = [pipeline.take_uplink()]
    uplink += fly(pipeline, Sender(system=1), 2, spoof=lambda i: ardupilot_heartbeat(intruder) if i % 10 == 0 else b"")
    assert len(pipeline.imu) == 100
    assert targets(uplink) == {1}  # no stream request went to system 99
    others = kinds(pipeline, "other_vehicle")
    assert [(e["system"], e["component"]) for e in others] == [(99, 1)]  # listed once
    assert "99" in others[0]["message"]


def test_without_a_pick_the_first_autopilot_heard_stays_the_vehicle():
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    vehicle, late = Sender(system=1), Sender(system=7)
    uplink = fly(pipeline, vehicle, 2, spoof=lambda i: ardupilot_heartbeat(late) + imu(late, 77_000_000 - i) if i % 5 == 0 else b"")
    assert len(pipeline.imu) == 100 and targets(uplink) == {1}
    assert [e["system"] for e in kinds(pipeline, "other_vehicle")] == [7]
    assert not kinds(pipeline, "device_reset")  # system 7's clock never reached the session's


def test_a_spoofer_on_the_vehicles_system_id_neither_arms_restarts_nor_inflates_the_losses():
    """A spoofer sending as system 1 from another component (pymavlink's default, 0): HEARTBEATs that
    flip arming and mode, and ATTITUDEs on a far-off clock, interleaved with the vehicle's stream."""
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    vehicle, spoofer = Sender(system=1, component=1), Sender(system=1, component=0)
    rng = random.Random(22)

    def spoof(i: int) -> bytes:
        spoofer.encoder.seq = rng.randrange(256)  # no sequence of its own
        armed = mavlink.MAV_MODE_FLAG_SAFETY_ARMED if i % 2 else 0
        beat = spoofer.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, DISARMED | armed, i % 7,
                                 mavlink.MAV_STATE_ACTIVE)
        battery = spoofer.sys_status(0, 0, 0, 0, 100 + i, 1, 1, 0, 0, 0, 0, 0, 0)  # a nearly flat battery
        return beat + spoofer.attitude(rng.randrange(1, 2**32 - 1), 1.0, -1.0, 2.0, 0, 0, 0) + battery

    uplink = fly(pipeline, vehicle, 4, spoof=spoof)
    pipeline.feed(6 * SECOND_NS, vehicle.sys_status(0, 0, 0, 0, 12_600, 500, 80, 0, 0, 0, 0, 0, 0))
    assert list(pipeline.tables["sys_status"].to_dict()["voltage_V"]) == [12.6]
    assert len(pipeline.tables["sys_status_1_0"]) == 200 and len(pipeline.tables["heartbeat_1_0"]) == 200  # kept apart
    assert len(kinds(pipeline, "vehicle_status")) == 1  # the vehicle's own, armed in mode 5, once
    assert pipeline.bank.armed is True
    assert not kinds(pipeline, "device_reset")
    assert len(pipeline.onboard) == 0  # the fake attitudes are nobody's estimate
    assert pipeline.decoder.stats.frames_lost == 0
    assert targets(uplink) == {1}


def test_the_lost_figure_is_the_vehicles_own():
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    vehicle = Sender(system=1)
    strangers = [Sender(system=s, component=c) for s in (40, 41) for c in (0, 1, 2)]
    rng = random.Random(5)

    def spoof(i: int) -> bytes:
        if i % 10 == 0:  # the vehicle's link loses 3 messages here
            vehicle.encoder.seq = (vehicle.encoder.seq + 3) % 256
        s = strangers[i % len(strangers)]
        s.encoder.seq = rng.randrange(256)
        return s.vfr_hud(1.0, 2.0, 3, 4, 5.0, 6.0)

    fly(pipeline, vehicle, 2, spoof=spoof)
    assert pipeline.decoder.stats.frames_lost == 3 * 10


def test_tables_are_bounded_and_the_bound_is_said_once():
    pipeline = Pipeline(("ahf",), protocol="mavlink")
    vehicle = Sender(system=1)
    pipeline.feed(SECOND_NS, ardupilot_heartbeat(vehicle) + vehicle.vfr_hud(1.0, 2.0, 3, 4, 5.0, 6.0))
    before = len(pipeline.tables)
    senders = [(s, c) for s in range(2, 255) for c in range(20)][:5000]
    for i, (s, c) in enumerate(senders):
        pipeline.feed(SECOND_NS + i, Sender(system=s, component=c).vfr_hud(1.0, 2.0, 3, 4, 5.0, 6.0))
    pipeline.feed(3 * SECOND_NS, vehicle.named_value_float(0, b"late", 1.0))  # the vehicle's own still get theirs
    added = set(pipeline.tables) - {"imu", "onboard", "mag_raw", "baro", "gps", "position", "heartbeat", "sys_status", "radio_status"}
    assert "vfr_hud" in added and "named_value_float" in added
    assert len(pipeline.tables) - before - 1 <= 256
    assert len(pipeline.catalogue.tables) == len(pipeline.tables)
    bound = [e for e in kinds(pipeline, "warning") if "tables" in e["message"]]
    assert len(bound) == 1
    assert pipeline.front.unplaced_messages == 5000 - (len(pipeline.tables) - before - 1)


@pytest.mark.parametrize("spec, system", [("mavlink:udpin:127.0.0.1:0?system=7", 7), ("mavlink:udpin:127.0.0.1:0", None)])
def test_the_vehicle_is_picked_in_the_spec(spec, system):
    source = open_source(spec)
    try:
        assert source.vehicle_system == system
    finally:
        source.close()


@pytest.mark.parametrize("value", ["0", "256", "x"])
def test_a_bad_system_is_a_clear_error(value):
    with pytest.raises(SourceError, match="bad system="):
        open_source(f"mavlink:udpin:127.0.0.1:0?system={value}")


def test_the_picked_vehicle_is_recorded_and_replayed_over_a_real_udp_link(tmp_path):
    """One UDP sender (the locked one) carrying two autopilots, the wrong one first: the session follows
    the picked system 1, and so does the replay of its recording."""
    import socket

    from groundstation.session_makers.load import load_session
    from groundstation.session_makers.factory import open_session
    from tests.waiting import wait_for

    session = open_session("mavlink:udpin:127.0.0.1:0?system=1", filters=("ahf",), recordings_dir=tmp_path)
    port = session.source.transport.local_address[1]
    intruder, vehicle = Sender(system=99), Sender(system=1)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp, session:
        for i in range(3):
            udp.sendto(ardupilot_heartbeat(intruder) + imu(intruder, 9_000_000 + i * 20_000), ("127.0.0.1", port))
        for i in range(100):
            udp.sendto((ardupilot_heartbeat(vehicle) if i % 50 == 0 else b"") + imu(vehicle, 5_000_000 + i * 20_000),
                       ("127.0.0.1", port))
        wait_for(lambda: len(session.pipeline.imu) == 100, what="the vehicle's 100 IMU samples")
    assert [e["system"] for e in kinds(session.pipeline, "other_vehicle")] == [99]
    data = load_session(session.recording_path)
    assert data.metadata["vehicle_system"] == 1
    np.testing.assert_array_equal(data.tables["imu"]["device_time_us"], session.pipeline.imu.to_dict()["device_time_us"])
    assert [e["system"] for e in data.events if e["kind"] == "other_vehicle"] == [99]

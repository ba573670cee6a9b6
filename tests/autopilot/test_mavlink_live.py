"""The live MAVLink path end to end on real parts: the simulated aircraft (pymavlink's encoder) on a
pseudo-terminal and over UDP on localhost, read by the ``mavlink:`` sources, decoded, rates requested
(and nothing else sent), the raw bytes saved as a .tlog and read back; values against simulator truth."""

import dataclasses
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from groundstation import quaternion
from groundstation.autopilot import records as rec
from groundstation.autopilot.decoder import MavlinkDecoder
from groundstation.session_makers.flight_log_session import read_log
from groundstation.autopilot.imu_rate import MIN_FILTER_RATE_HZ
from groundstation.autopilot.streams import StreamRequester
from groundstation.autopilot.tlog import packets_of_chunks, write_tlog
from groundstation.sim.mavlink_aircraft import ACC_NOISE_G, GYR_NOISE_RAD_S, MavlinkAircraft
from groundstation.sim.stream import Scenario
from groundstation.sources import SourceClosed, SourceError, open_source
from groundstation.units import STANDARD_GRAVITY_M_S2
from mavlink_helpers import Flying
from tests.waiting import LIMIT_S

SCENARIO = dataclasses.replace(Scenario(), profile="flight", duration_s=60.0, seed=3)


def session(source, seconds: float, quiet_s: float = 1.2):
    """Read, decode and answer like a live session would until ``seconds`` of the aircraft's IMU time have
    arrived (the uplink held back for its first ``quiet_s``, so the rate before the request shows);
    returns (chunks, records, requester, decoder). The aircraft's time, not the wall clock: a loaded
    machine (a bridge process slow to start) only makes it take longer."""
    decoder, requester = MavlinkDecoder(), StreamRequester(rate_hz=50.0)
    chunks, records, imu_us = [], [], []
    deadline = time.monotonic() + LIMIT_S

    def imu_s() -> float:
        return (imu_us[-1] - imu_us[0]) / 1e6 if imu_us else 0.0

    while imu_s() < seconds:
        assert time.monotonic() < deadline, f"{seconds:g} s of IMU samples: not within {LIMIT_S:g} s"
        chunk = source.read()
        if chunk is None:
            continue
        chunks.append(chunk)
        new = decoder.feed(chunk.data, chunk.t_host_ns)
        records += new
        imu_us += [r.time_us for r in new if isinstance(r, rec.ImuSample)]
        uplink = requester.update(new, chunk.t_host_ns) if imu_s() > quiet_s else b""
        if uplink:
            source.write(uplink)
    return chunks, records, requester, decoder


def check_against_truth(aircraft: MavlinkAircraft, records):
    imu = [r for r in records if isinstance(r, rec.ImuSample)]
    t_s = np.array([r.time_us for r in imu]) / 1e6
    truth = aircraft.profile.truth(t_s)
    acc = np.array([r.acc_g for r in imu])
    gyr = np.array([r.gyr_rad_s for r in imu])
    # White noise plus rounding to 1 mG / 1 mrad/s: within 5 sigma + half a count everywhere.
    assert np.abs(acc - truth.specific_force_body_m_s2() / STANDARD_GRAVITY_M_S2).max() < 5 * ACC_NOISE_G + 0.0005
    assert np.abs(gyr - truth.rate_body_rad_s).max() < 5 * GYR_NOISE_RAD_S + 0.0005
    board = [r for r in records if isinstance(r, rec.OnboardAttitude)]
    q_true = aircraft.profile.truth(np.array([r.time_us for r in board]) / 1e6).q_body_to_ned
    assert np.degrees(quaternion.angle_between(np.array([r.q for r in board]), q_true)).max() < 1e-3  # float32 angles
    return imu


def check_rates_requested(aircraft, requester, imu):
    assert ("RAW_IMU", 0.02) in aircraft.requests and ("ATTITUDE", 0.02) in aircraft.requests
    assert aircraft.refused == []  # only stream requests went up: nothing that arms or moves it
    dt = np.diff([r.time_us for r in imu]) / 1e6
    assert np.median(dt[:3]) == pytest.approx(0.25)  # 4 Hz before the request
    rate_hz = requester.monitor.rate_hz
    assert rate_hz == pytest.approx(50.0, rel=0.02) and rate_hz >= MIN_FILTER_RATE_HZ


@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")
def test_pty_live_session_requests_rates_matches_truth_and_saves_a_tlog(tmp_path):
    from groundstation.sim.pty_bridge import PtyBridge

    aircraft = MavlinkAircraft(SCENARIO)
    bridge = PtyBridge(aircraft)
    source = open_source(f"mavlink:{bridge.path}?baud=57600")
    assert (source.is_replay, source.can_send, source.can_reopen) == (False, True, True) and "57600" in source.description
    try:
        with Flying(bridge):
            chunks, records, requester, decoder = session(source, 3.0)
    finally:
        source.close()
    imu = check_against_truth(aircraft, records)
    check_rates_requested(aircraft, requester, imu)
    assert decoder.senders[(1, 1)].lost == 0 and decoder.stats.bad_bytes == 0
    assert any(isinstance(r, rec.LinkHealth) and r.system == 51 for r in records)
    # The raw bytes (what the session records) saved as a standard .tlog hold the same IMU stream.
    path = tmp_path / "live.tlog"
    write_tlog(path, packets_of_chunks([(c.t_host_ns, c.data) for c in chunks], 1_700_000_000_000_000))
    log = read_log(path)
    assert np.array_equal(log.imu.time_us, [r.time_us for r in imu])
    assert np.allclose(log.imu.stack(["acc_x_g", "acc_y_g", "acc_z_g"]), [r.acc_g for r in imu])
    # ... and replay as a source, packet by packet, to the same records.
    replay = open_source(f"mavlink:{path}")
    assert replay.is_replay and not replay.can_send
    again = MavlinkDecoder()
    replayed = []
    with pytest.raises(SourceClosed):
        while True:
            chunk = replay.read()
            replayed += again.feed(chunk.data, chunk.t_host_ns)
    assert [r.time_us for r in replayed if isinstance(r, rec.ImuSample)] == [r.time_us for r in imu]


def test_udp_live_session_mavlink1():
    from groundstation.sim.udp_bridge import UdpBridge

    aircraft = MavlinkAircraft(SCENARIO, mavlink1=True)
    source = open_source("mavlink:udpin:127.0.0.1:0")
    bridge = UdpBridge(aircraft, ("127.0.0.1", source.transport.local_address[1]))
    try:
        with Flying(bridge):
            chunks, records, requester, decoder = session(source, 3.0)
    finally:
        source.close()
    assert all(c.data[0] == 0xFE for c in chunks)  # MAVLink 1 packets, one datagram each
    imu = check_against_truth(aircraft, records)
    check_rates_requested(aircraft, requester, imu)


def test_bridge_sim_command_sends_mavlink_over_udp():
    source = open_source("mavlink:udpin:127.0.0.1:0")
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--udp", f"127.0.0.1:{source.transport.local_address[1]}",
                                "--duration", "3", "--seed", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        _, records, requester, _ = session(source, 2.5)  # of the bridge's 3 s
        out, err = process.communicate(timeout=LIMIT_S)
    finally:
        process.kill()
        source.close()
    assert process.returncode == 0 and "MAVLink on udp 127.0.0.1" in out
    assert any(isinstance(r, rec.VehicleStatus) and r.mode == "STABILIZE" and not r.armed for r in records)
    assert "('RAW_IMU', 0.02)" in err and "refused commands []" in err


@pytest.mark.parametrize("spec, message", [
    ("mavlink:", "name a serial port"),
    ("mavlink:udpin:14550", "HOST:PORT"),
    ("mavlink:tcp:127.0.0.1:notaport", "bad address"),
    ("mavlink:/dev/ttyUSB0?baud=fast", "bad baud"),
    ("mavlink:/dev/ttyUSB0?speed=2", "unknown option speed"),
    ("mavlink:/no/such/port", "cannot open serial port"),
    ("mavlink:/no/such/file.tlog", "cannot open"),
    ("mavlink:tcp:127.0.0.1:1", "cannot open"),
    ("mavlonk:/dev/ttyUSB0", "unknown source scheme"),
])  # fmt: skip
def test_bad_specs_are_clear_errors(spec, message):
    with pytest.raises(SourceError, match=message):
        open_source(spec)


def test_a_busy_udp_port_is_a_clear_error():
    first = open_source("mavlink:udpin:127.0.0.1:0")
    try:
        with pytest.raises(SourceError, match="cannot listen"):
            open_source(f"mavlink:udpin:127.0.0.1:{first.transport.local_address[1]}")
    finally:
        first.close()


def test_udpout_introduces_itself_with_a_gcs_heartbeat_and_reads_the_answers():
    import socket

    vehicle = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    vehicle.bind(("127.0.0.1", 0))
    vehicle.settimeout(2.0)
    source = open_source(f"mavlink:udpout:127.0.0.1:{vehicle.getsockname()[1]}")
    try:
        hello, gcs = vehicle.recvfrom(1024)
        (heartbeat,) = MavlinkDecoder().messages(hello)
        assert heartbeat.get_type() == "HEARTBEAT" and heartbeat.type == 6 and heartbeat.get_srcSystem() == 255  # MAV_TYPE_GCS
        aircraft = MavlinkAircraft(SCENARIO)
        vehicle.sendto(b"".join(c.data for c in aircraft.advance(1.0)), gcs)
        chunk = None
        while chunk is None:
            chunk = source.read()
        assert any(isinstance(r, rec.ImuSample) for r in MavlinkDecoder().feed(chunk.data))
    finally:
        source.close()
        vehicle.close()

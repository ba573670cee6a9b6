"""Through a real pseudo-terminal with pyserial on the other end, at 100 Hz in real time."""

import os
import signal
import subprocess
import sys
import threading
import time

import pytest
import serial

import firmware_protocol as fp
from groundstation.sim.link import LinkSettings
from groundstation.sim.stream import Scenario, SimStream

from sim_helpers import ENUM, assert_decoder_agrees_with_link, read_for

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")


def test_pyserial_reads_what_the_link_model_says_it_delivered():
    from groundstation.sim.pty_bridge import PtyBridge

    link = LinkSettings(loss=0.03, burst_loss=0.03, burst_length_frames=5, ber=3e-4, truncate=0.02)
    bridge = PtyBridge(SimStream(Scenario("flight", 60.0, seed=21, link=link)))
    port = serial.Serial(bridge.path, baudrate=115200, timeout=0.05)  # open before streaming: no byte missed
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop.is_set,))
    thread.start()
    decoder = fp.StreamDecoder()
    try:
        frames = read_for(port, decoder, 4.0)
        stop.set()
        thread.join()
        frames += read_for(port, decoder, 0.3)
    finally:
        stop.set()
        port.close()
        bridge.close()
    report = bridge.stream.link.report
    assert bridge.bytes_dropped == 0 and report.lost > 0 and report.truncated + report.corrupted > 0
    assert_decoder_agrees_with_link(decoder, frames, bridge.stream)
    assert 230 < sum(f.name == "IMU_RAW" for f in frames) < 310  # 100 Hz after the 1 s boot, less the lost


def start_cli(*args: str) -> tuple[subprocess.Popen, str]:
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", *args],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    first_line = process.stdout.readline()
    assert first_line, process.stderr.read()
    return process, first_line.split()[-1]


def test_cli_bridge_streams_at_100_hz_obeys_commands_and_stops_on_sigterm():
    process, path = start_cli("--scenario", "hover", "--seed", "3")
    try:
        with serial.Serial(path, baudrate=9600, timeout=0.05) as port:  # any baud rate works
            decoder = fp.StreamDecoder()
            frames = read_for(port, decoder, 2.5)
            imu = [f for f in frames if f.name == "IMU_RAW"]
            rate_hz = (len(imu) - 1) / ((imu[-1].device_time_us - imu[0].device_time_us) * 1e-6)
            assert 99.0 < rate_hz < 101.0 and decoder.stats.crc_errors == 0
            port.write(fp.encode(fp.make_frame("COMMAND", seq=77, command=ENUM["command"]["set_mode"],
                                               param=ENUM["mode"]["raw"], value=0.0)))
            after = read_for(port, decoder, 1.0)
        acks = [f for f in after if f.name == "ACK"]
        assert [(f["command_seq"], f["result"]) for f in acks] == [(77, ENUM["ack_result"]["ok"])]
        tail = after[after.index(acks[0]) :]
        assert [f["mode"] for f in tail if f.name == "CONFIG"] == [ENUM["mode"]["raw"]]
        assert not any(f.name == "ATTITUDE" for f in tail) and sum(f.name == "IMU_RAW" for f in tail) > 50
    finally:
        process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=10)
    assert process.returncode == 0, err
    assert "link:" in err and "Traceback" not in err


def test_port_disappears_and_comes_back_under_the_same_name(tmp_path):
    name = str(tmp_path / "ttySIM")
    process, path = start_cli("--scenario", "static", "--dropout-every", "1.5", "--dropout-s", "0.5", "--link", name)
    assert path == name
    sessions = []
    try:
        end = time.monotonic() + 4.5
        while time.monotonic() < end and len(sessions) < 2:
            try:
                port = serial.Serial(path, timeout=0.05)
            except (serial.SerialException, OSError):
                time.sleep(0.05)  # gone: wait for it to come back
                continue
            decoder, frames = fp.StreamDecoder(), []
            try:
                while time.monotonic() < end:
                    frames += decoder.feed(port.read(port.in_waiting or 1))
            except serial.SerialException:
                sessions.append(frames)  # the device vanished under the reader
            finally:
                port.close()
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=10)
    assert len(sessions) == 2 and all(sum(f.name == "IMU_RAW" for f in s) > 20 for s in sessions)
    assert not os.path.lexists(name)


def test_a_board_rebooting_mid_session_through_the_pty(tmp_path):
    """``bridge-sim --reboot-after``: a live session over pyserial records one device_reset, keeps its
    time monotonic and in step with the host clock, and a replay of its recording finds the same."""
    import numpy as np

    from groundstation.session_makers.load import load_session
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.sources import SerialSource

    process, path = start_cli("--scenario", "hover", "--seed", "4", "--reboot-after", "3")
    try:
        session = LiveSession(SerialSource(path), Pipeline(), recordings_dir=tmp_path)
        with session:
            deadline = time.monotonic() + 20  # however slow the machine is today
            while time.monotonic() < deadline and not (
                any(e["kind"] == "device_reset" for e in session.pipeline.events) and len(session.pipeline.imu) > 500
            ):
                time.sleep(0.1)
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=10)
    pipeline = session.pipeline
    resets = [e for e in pipeline.events if e["kind"] in ("device_reset", "clock_jump")]
    assert [e["kind"] for e in resets] == ["device_reset"]
    assert resets[0]["device_time_us_after"] < resets[0]["device_time_us_before"]
    imu = pipeline.imu.to_dict()
    assert np.all(np.diff(imu["time_s"]) > 0)
    samples = np.isfinite(imu["device_time_us"])
    assert (~samples).sum() == 1  # the gap row
    # In step with the host clock: apart from delivery delays (a busy machine's included).
    lag_s = imu["host_time_s"][samples] - imu["time_s"][samples]
    assert lag_s.max() - lag_s.min() < 1.0
    assert pipeline.decoder.stats.frames_lost == 0 and pipeline.decoder.stats.restarts == 1
    replayed = load_session(session.recording_path)
    assert [e["kind"] for e in replayed.events if e["kind"] == "device_reset"] == ["device_reset"]
    np.testing.assert_array_equal(replayed.tables["imu"]["time_s"], imu["time_s"])

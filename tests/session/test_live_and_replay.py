"""End to end through a real pseudo-terminal: bridge -> serial source -> recording -> replay."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.live import LiveSession
from groundstation.session_makers.pipeline import Pipeline
from groundstation.session_makers.replay import replay
from groundstation.sources import SerialSource
from tests.waiting import wait_for

pytestmark = pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals are POSIX only")


@pytest.fixture
def bridge():
    process = subprocess.Popen(
        [sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "flight", "--mode", "both", "--seed", "3"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    path = process.stdout.readline().split()[-1]
    yield path
    process.terminate()
    process.wait(timeout=10)


def run_live(path, tmp_path, seconds: float, settings_change_at: float | None = None) -> LiveSession:
    session = LiveSession(SerialSource(path, 115200), Pipeline(("ahf", "hf", "ecf")), recordings_dir=tmp_path)
    with session:
        deadline = time.monotonic() + seconds
        changed = False
        while time.monotonic() < deadline:
            time.sleep(0.05)
            if settings_change_at is not None and not changed and time.monotonic() > deadline - seconds + settings_change_at:
                session.change_settings("hf", {"beta": 0.3})
                changed = True
    return session


def test_replay_of_a_live_recording_reproduces_the_live_estimates_bit_for_bit(bridge, tmp_path):
    live = run_live(bridge, tmp_path, seconds=4.0, settings_change_at=2.0)
    live_imu = live.pipeline.imu.array()
    assert len(live_imu) > 250  # ~100 Hz for 4 s, after the boot second
    assert live.pipeline.config is not None and live.pipeline.sensor.gyro_fs_dps in (250, 500, 1000, 2000)
    assert any(e["kind"] == "settings" for e in live.pipeline.events)

    recording = open_recording(live.recording_path)
    assert recording.damage == [] and recording.closed_cleanly
    replayed = replay(recording).imu.array()
    np.testing.assert_array_equal(replayed, live_imu)  # bit-identical, NaN-free
    np.testing.assert_array_equal(replay(recording).imu.array(), replayed)  # and again

    # The settings change is real: HF before and after differs from a replay without it.
    without_change = replay(recording, forced={"hf": {"beta": 0.1}}).imu
    hf = live.pipeline.imu.columns.index("hf_qw")
    assert not np.array_equal(without_change.array()[:, hf], live_imu[:, hf])


def test_live_link_statistics_match_the_decoder(bridge, tmp_path):
    live = LiveSession(SerialSource(bridge, 115200), Pipeline(("ahf",)), recordings_dir=tmp_path)
    with live:
        deadline = time.monotonic() + 20  # three full seconds of link, however slow the machine is today
        while len(live.pipeline.link.per_second) < 3 and time.monotonic() < deadline:
            time.sleep(0.05)
    p = live.pipeline
    assert p.decoder.stats.crc_errors == 0 and p.decoder.stats.frames_lost == 0  # the default link is clean
    per_second = p.link.per_second.array()
    assert len(per_second) >= 2
    # a full second carries 100 IMU_RAW + 100 ATTITUDE (+1 STATUS) frames at mode "both"
    assert 190 <= per_second[1, 1] <= 210
    clock = p.link.clock()
    assert clock["latency_p99_ms"] < 100


def test_an_unplugged_port_is_reopened_when_it_comes_back(tmp_path):
    link = tmp_path / "radio"
    process = subprocess.Popen(
        [sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "hover", "--dropout-every", "2", "--dropout-s", "1",
         "--link", str(link)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )
    try:
        process.stdout.readline()
        session = LiveSession(SerialSource(str(link)), Pipeline(), recordings_dir=tmp_path)
        with session:  # waits for what it checks: on a loaded machine the port's 1 s up can pass with few rows
            wait_for(lambda: any(e["kind"] == "reconnected" for e in session.pipeline.events), what="reconnected")
            rows_at_reconnect = len(session.pipeline.imu)
            wait_for(lambda: len(session.pipeline.imu) > rows_at_reconnect + 50, what="data after reconnecting")
    finally:
        process.terminate()
        process.wait(timeout=10)
    kinds = [e["kind"] for e in session.pipeline.events]
    assert "disconnected" in kinds and "reconnected" in kinds
    assert session.error is None
    recorded = [e["kind"] for _, e in open_recording(session.recording_path).events]
    assert "disconnected" in recorded and "reconnected" in recorded  # the recording says what happened

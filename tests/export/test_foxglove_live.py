"""The live Foxglove bridge, as a Foxglove client sees it: a WebSocket client speaking the Foxglove
protocol (``foxglove.sdk.v1``, written here from the protocol's description, not the SDK's) subscribes
to every channel, and 10 s of a live 100 Hz session arrive with nothing lost against the session's own
tables."""

import subprocess
import sys
import time

import numpy as np
import pytest
from groundstation.errors import UserError

from groundstation.export.foxglove_live import FoxgloveBridge, parse_address
from groundstation.export.protobuf_rows import field_names
from groundstation.session_makers.factory import open_session
from tests.foxglove_client import Client, decoded

def test_ten_seconds_of_a_live_session_arrive_whole(tmp_path):
    session = open_session("sim:?scenario=hover&seed=3", filters=("ahf", "hf"), record=False)
    bridge = FoxgloveBridge("127.0.0.1", 0).serve(session)
    client = Client(bridge.port)
    try:
        assert client.ready.wait(10), "no channels advertised"
        time.sleep(0.5)  # the subscriptions reach the server
        with session:
            time.sleep(10.0)
        bridge.pump()
        expected = len(session.view.tables["imu"])
        deadline = time.monotonic() + 60  # a loaded machine: the client thread may lag behind the server
        while len(client.messages.get("/imu", [])) < expected and time.monotonic() < deadline:
            time.sleep(0.1)
        bridge.close()
    finally:
        client.stop.set()
        client.thread.join(5)
    imu = session.view.tables["imu"]
    rows = imu.array()
    assert len(rows) > 900  # 10 s at 100 Hz
    frames = {c["topic"]: c for c in client.channels.values()}
    got = decoded(client, "/imu")
    assert len(got) == len(rows)
    for i, (column, field) in enumerate(zip(imu.columns, field_names(imu.columns))):
        read = np.array([getattr(m, field) for m in got], dtype=float)
        np.testing.assert_array_equal(read, rows[:, i], err_msg=column)  # bit for bit, NaN as NaN
    times = np.array([t for t, _ in client.messages["/imu"]], dtype=np.int64)
    np.testing.assert_allclose(np.diff(times) / 1e9, np.diff(rows[:, 0]), atol=2e-9)  # log time follows session time
    assert abs(times[0] / 1e9 - time.time()) < 60  # wall-clock time of day
    onboard = session.view.tables["onboard"]
    assert len(client.messages["/onboard"]) == len(onboard) > 900
    assert frames["/tf"]["schemaName"] == "foxglove.FrameTransforms"
    assert len(client.messages["/tf"]) >= len(rows) - 5  # one per sample (those with a converged estimate)
    assert {"/attitude/ahf", "/attitude/hf", "/attitude/onboard", "/events"} <= set(frames)


def test_addresses():
    assert parse_address("8765") == ("127.0.0.1", 8765)
    assert parse_address("0.0.0.0:9000") == ("0.0.0.0", 9000)
    for bad in ("x", "70000", "host:", "-1"):
        with pytest.raises(UserError, match=r"\[HOST:\]PORT"):
            parse_address(bad)


def test_record_serves_foxglove_and_says_where(tmp_path):
    process = subprocess.Popen([sys.executable, "-m", "groundstation", "record", "--port", "sim:?seed=1",
                                "--duration", "4", "--recordings", str(tmp_path), "--foxglove", "127.0.0.1:0"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out, err = process.communicate(timeout=120)
    assert process.returncode == 0, err
    assert "serving Foxglove on ws://127.0.0.1:" in out


def test_a_taken_port_is_said_in_one_line(tmp_path):
    first = FoxgloveBridge("127.0.0.1", 0)
    try:
        done = subprocess.run([sys.executable, "-m", "groundstation", "record", "--port", "sim:?seed=1", "--duration",
                               "1", "--recordings", str(tmp_path), "--foxglove", f"127.0.0.1:{first.port}"],
                              capture_output=True, text=True, timeout=120)
    finally:
        first.close()
    assert done.returncode == 2 and "cannot serve Foxglove" in done.stderr and "Traceback" not in done.stderr
    assert not list(tmp_path.iterdir())  # refused before anything was opened or recorded

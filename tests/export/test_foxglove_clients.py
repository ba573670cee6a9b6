"""The live Foxglove bridge as the clients users have see it: Foxglove's own npm client
(``@foxglove/ws-protocol`` 0.8.0 on node, tests/js_ws/) with either name of the protocol; a web page of a
foreign origin refused; the number of clients capped; ten clients that never read cost the server little
memory, none of it kept after they leave, and the recording meanwhile loses nothing.

The npm packages are installed once per lock file (``npm ci``) into a cache folder outside the work tree."""

import base64
import hashlib
import json
import os
import select
import shutil
import socket as socket_module
import subprocess
from pathlib import Path

import numpy as np
import pytest
import websockets
from mcap.records import Schema
from mcap_protobuf.decoder import DecoderFactory
from websockets.sync.client import connect

from groundstation.export.foxglove_live import SUBPROTOCOLS, FoxgloveBridge, origin_allowed
from groundstation.export.protobuf_rows import field_names
from groundstation.session_makers.factory import open_session
from groundstation.session_makers.load import load_session
from tests.waiting import wait_for

JS = Path(__file__).resolve().parents[1] / "js_ws"


@pytest.fixture(scope="session")
def node_modules() -> Path:
    """``npm ci`` of tests/js_ws into ~/.cache (or $XDG_CACHE_HOME), once per version of its lock file."""
    if not (shutil.which("node") and shutil.which("npm")):
        pytest.skip("node and npm are needed to run Foxglove's npm client")
    lock = (JS / "package-lock.json").read_bytes()
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "groundstation-tests"
    folder = cache / f"js_ws-{hashlib.sha256(lock).hexdigest()[:16]}"
    if not (folder / "node_modules" / ".package-lock.json").exists():
        building = cache / f"{folder.name}.{os.getpid()}"  # two test processes may install at once
        shutil.rmtree(building, ignore_errors=True)
        building.mkdir(parents=True)
        for name in ("package.json", "package-lock.json"):
            shutil.copy(JS / name, building / name)
        done = subprocess.run(["npm", "ci", "--ignore-scripts", "--no-audit", "--no-fund"], cwd=building,
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        try:
            building.rename(folder)
        except OSError:  # the other process was first
            shutil.rmtree(building, ignore_errors=True)
    return folder / "node_modules"


class NodeClient:
    """tests/js_ws/client.cjs in a process of its own: Foxglove's FoxgloveClient, subscribing to everything."""

    def __init__(self, node_modules: Path, port: int, subprotocol: str, origin: str | None = None):
        self.process = subprocess.Popen(["node", str(JS / "client.cjs"), f"ws://127.0.0.1:{port}", subprotocol,
                                         *([origin] if origin else [])], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True, env={**os.environ, "NODE_PATH": str(node_modules)})

    def advertised(self) -> dict:
        ready, _, _ = select.select([self.process.stdout], [], [], 60)  # generous: a loaded machine, node starting
        assert ready, "the npm client said nothing in 60 s"
        line = self.process.stdout.readline()  # the first advertise (or the close, when refused)
        assert line, self.process.stderr.read()
        return json.loads(line)

    def closed(self) -> dict:
        out, err = self.process.communicate(timeout=120)
        lines = [json.loads(line) for line in out.splitlines()]
        assert lines and lines[-1]["event"] == "closed", err
        return lines[-1]


def live_session(tmp_path, record=False):
    return open_session("sim:?scenario=hover&seed=3", filters=("ahf", "hf"), record=record, recordings_dir=tmp_path)


@pytest.mark.parametrize("subprotocol", SUBPROTOCOLS)
def test_foxglove_npm_client_receives_the_session_with_either_subprotocol(node_modules, tmp_path, subprotocol):
    session = live_session(tmp_path)
    bridge = FoxgloveBridge("127.0.0.1", 0).serve(session)
    client = NodeClient(node_modules, bridge.port, subprotocol)
    try:
        assert "/imu" in client.advertised()["topics"]  # the session's channels, before its first row
        with session:
            wait_for(lambda: len(session.view.tables["imu"]) >= 300, 60, "3 s of the session")
    finally:
        bridge.close()
    got = client.closed()
    assert got["protocol"] == subprotocol and got["serverInfo"]["name"] == "groundstation" and not got["errors"]
    channels = {c["topic"]: c for c in got["channels"]}
    assert channels["/tf"]["schemaName"] == "foxglove.FrameTransforms" and channels["/tf"]["encoding"] == "protobuf"
    advertised = channels["/imu"]  # protobuf: the FileDescriptorSet in base64 (the protocol's rule for binary schemas)
    assert advertised["encoding"] == "protobuf" and advertised["schemaName"] == "groundstation.imu"
    schema = Schema(id=0, name=advertised["schemaName"], encoding=advertised["schemaEncoding"],
                    data=base64.b64decode(advertised["schema"]))
    decode = DecoderFactory().decoder_for(advertised["encoding"], schema)
    imu = session.view.tables["imu"]
    rows = imu.array()
    messages = [decode(base64.b64decode(payload)) for _, payload in got["messages"]["/imu"]]
    assert len(messages) == len(rows)
    for i, (column, field) in enumerate(zip(imu.columns, field_names(imu.columns))):
        read = np.array([getattr(m, field) for m in messages], dtype=float)
        np.testing.assert_array_equal(read, rows[:, i], err_msg=column)  # bit for bit, NaN as NaN
    times = np.array([int(t) for t, _ in got["messages"]["/imu"]], dtype=np.int64)
    np.testing.assert_allclose(np.diff(times) / 1e9, np.diff(rows[:, 0]), atol=2e-9)  # log time follows session time
    assert len(got["messages"]["/onboard"]) == len(session.view.tables["onboard"])
    assert {"/onboard", "/attitude/ahf", "/attitude/hf", "/attitude/onboard"} <= set(got["messages"])


def test_a_page_of_another_origin_is_refused(node_modules, tmp_path):
    bridge = FoxgloveBridge("127.0.0.1", 0)
    try:
        got = NodeClient(node_modules, bridge.port, SUBPROTOCOLS[1], origin="https://evil.example").closed()
        assert any("403" in e for e in got["errors"]) and got["serverInfo"] is None and not got["messages"]
        for origin in ("http://localhost:8080", "https://app.foxglove.dev", None):  # a local page, a web app, a native app
            with connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[0]], origin=origin) as socket:
                assert json.loads(socket.recv(timeout=30))["op"] == "serverInfo"
        with pytest.raises(websockets.InvalidStatus, match="403"):
            connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[0]], origin="http://localhost.evil.example")
        assert bridge.refused == 2
    finally:
        bridge.close()


def test_native_only_refuses_every_page():
    bridge = FoxgloveBridge("127.0.0.1", 0, web_apps=False)
    try:
        with connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[1]]) as socket:  # a native app
            assert json.loads(socket.recv(timeout=30))["op"] == "serverInfo"
        for origin in ("http://localhost:8080", "https://app.foxglove.dev"):
            with pytest.raises(websockets.InvalidStatus, match="403"):
                connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[0]], origin=origin)
    finally:
        bridge.close()


def test_which_origins_are_served():
    for origin in ("http://localhost:3000", "http://127.0.0.1", "http://[::1]:8080", "https://app.foxglove.dev",
                   "https://lichtblick-suite.github.io"):
        assert origin_allowed(origin, web_apps=True) and not origin_allowed(origin, web_apps=False), origin
    for origin in ("https://example.com", "null", "http://localhost.example.com", "https://app.foxglove.dev.example.com",
                   "file://localhost", "https://evil.example/https://app.foxglove.dev"):
        assert not origin_allowed(origin, web_apps=True), origin
    assert origin_allowed(None, web_apps=False)  # a native app


def test_a_client_beyond_the_cap_is_told_why(node_modules):
    bridge = FoxgloveBridge("127.0.0.1", 0, max_clients=2)
    first = connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[0]]).__enter__()
    second = connect(f"ws://127.0.0.1:{bridge.port}", subprotocols=[SUBPROTOCOLS[1]]).__enter__()
    try:
        wait_for(lambda: bridge.clients == 2, what="two clients")
        got = NodeClient(node_modules, bridge.port, SUBPROTOCOLS[1]).closed()
        assert got["code"] == 1013 and "at most 2" in got["reason"]
        assert [s["level"] for s in got["statuses"]] == [2]
        assert "at most 2 Foxglove clients" in got["statuses"][0]["message"] and bridge.refused == 1
    finally:
        first.close()
        second.close()
        bridge.close()


def rss_bytes() -> int:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmRSS:"))


def stalled_clients(port: int, count: int) -> list:
    """``count`` clients that subscribe to every channel and then read nothing more."""
    sockets = []
    for _ in range(count):
        # max_queue=1: the client's reader stops taking frames off the socket after one it was not asked for;
        # a small receive buffer (set before connecting: it sets the window) so that the server's queue, not
        # the kernel's buffers of megabytes, is what fills (in seconds, however small the messages).
        raw = socket_module.socket(socket_module.AF_INET, socket_module.SOCK_STREAM)
        raw.setsockopt(socket_module.SOL_SOCKET, socket_module.SO_RCVBUF, 4096)
        raw.connect(("127.0.0.1", port))
        socket = connect(f"ws://127.0.0.1:{port}", sock=raw, subprotocols=[SUBPROTOCOLS[0]], max_queue=1).__enter__()
        assert json.loads(socket.recv(timeout=30))["op"] == "serverInfo"
        channels = json.loads(socket.recv(timeout=30))["channels"]
        socket.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": i, "channelId": c["id"]} for i, c in enumerate(channels)]}))
        sockets.append(socket)
    return sockets


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the process's RSS from /proc")
def test_ten_clients_that_never_read_cost_little_memory_and_the_recording_nothing(tmp_path):
    """Twice ten clients that stop reading once subscribed, until each one's queue is full and drops: the
    process (server and these clients) grows by less than 50 MB; after they leave it keeps less than 20 MB
    of it (what the allocator keeps for reuse, and the live session's own tables growing meanwhile: a
    few MB a minute), and the second ten take no more than the first (nothing leaks per client)."""
    session = live_session(tmp_path, record=True)
    bridge = FoxgloveBridge("127.0.0.1", 0).serve(session)
    rounds = []
    try:
        with session:
            wait_for(lambda: len(session.view.tables["imu"]) >= 200, 60, "2 s of the session")
            before = rss_bytes()
            for _ in range(2):
                sockets = stalled_clients(bridge.port, 10)
                wait_for(lambda: len(bridge.queues()) == 10 and all(dropped > 0 for _, dropped in bridge.queues()),
                         120, "every client's queue full")
                during = rss_bytes()
                for socket in sockets:
                    socket.close_socket()  # gone without a word, as a killed app
                wait_for(lambda: bridge.clients == 0, 60, "the clients gone")
                rounds.append((during, rss_bytes()))
    finally:
        bridge.close()
    for during, after in rounds:
        print(f"\nRSS before {before / 2**20:.1f} MiB, 10 clients that never read {during / 2**20:.1f} MiB, "
              f"after they left {after / 2**20:.1f} MiB")
        assert during - before < 50 * 2**20 and after - before < 20 * 2**20
    assert rounds[1][0] - rounds[0][0] < 4 * 2**20  # the second ten reuse what the first left
    assert bridge.dropped > 0 and "messages dropped for slow clients" in bridge.status_text()
    counters = session.view.counters()
    assert counters["frames_lost"] == 0 and counters["crc_errors"] == 0 and counters["bytes_skipped"] == 0
    replayed = load_session(session.recording_path)
    assert len(replayed.tables["imu"]["time_s"]) == len(session.view.tables["imu"])

"""UDP and TCP bridges over real sockets on 127.0.0.1, streaming the simulated aircraft's bytes
into a session opened by spec: every byte arrives, is recorded, decoded, and uplink reaches the
aircraft (its ACKs come back)."""

from groundstation.recording import open_recording
from groundstation.session_makers.factory import open_session
from tests.waiting import LIMIT_S, wait_for

from .bridges import TcpBridge, UdpBridge


def acked(session, seq: int) -> bool:
    with session.lock:
        return any(e["kind"] == "ack" and e["command_seq"] == seq for e in session.pipeline.events)


def test_udp_bridge_every_datagram_arrives_and_uplink_goes_back_to_the_sender(tmp_path):
    session = open_session("udp://127.0.0.1:0", filters=("ahf",), recordings_dir=tmp_path)
    assert (session.source.can_send, session.source.can_reopen, session.source.is_replay) == (True, True, False)
    bridge = UdpBridge(session.source.local_address)
    with session:  # start() asks for CONFIG before any datagram came: held until the bridge is heard
        bridge.start()
        wait_for(lambda: len(session.pipeline.imu) > 100)
        wait_for(lambda: acked(session, 0))  # the request held until the bridge was heard reached it
        seq = session.send_command("request_config")
        wait_for(lambda: acked(session, seq))
        bridge.close()
        wait_for(lambda: session.pipeline.decoder.stats.bytes_in >= len(bridge.sent), what="the last datagrams in flight")
    stats = session.pipeline.decoder.stats
    assert stats.bytes_in == len(bridge.sent) and stats.crc_errors == 0 and stats.frames_lost == 0
    recording = open_recording(session.recording_path)
    assert b"".join(data for _, data in recording.chunks()) == bytes(bridge.sent)  # one chunk per datagram, in order
    assert bridge.uplink.count(b"\xa5") >= 2  # both COMMAND frames went back to the bridge's own port


def test_tcp_bridge_streams_and_the_session_reconnects_when_the_bridge_drops(tmp_path):
    bridge = TcpBridge().start()
    try:
        session = open_session(f"tcp://127.0.0.1:{bridge.port}", filters=("ahf",), recordings_dir=tmp_path)
        assert session.source.description == f"TCP bridge 127.0.0.1:{bridge.port}"
        with session:
            wait_for(lambda: len(session.pipeline.imu) > 100)
            seq = session.send_command("request_config")
            wait_for(lambda: acked(session, seq))
            bridge.drop()  # the ESP32 rebooted
            wait_for(lambda: any(e["kind"] == "reconnected" for e in session.pipeline.events))
            rows = len(session.pipeline.imu)
            wait_for(lambda: len(session.pipeline.imu) > rows + 50)  # data flows again
            bridge.close()
            wait_for(lambda: session.pipeline.decoder.stats.bytes_in >= len(bridge.sent), what="the last bytes in flight")
    finally:
        bridge.close()
    kinds = [e["kind"] for e in session.pipeline.events]
    assert kinds.index("disconnected") < kinds.index("reconnected") and session.error is None
    assert bridge.connections == 2
    assert session.pipeline.decoder.stats.bytes_in == len(bridge.sent)  # nothing lost on either connection
    assert session.pipeline.decoder.stats.crc_errors == 0


def test_udp_without_a_host_listens_on_this_machine_only(tmp_path):
    from groundstation.sources import open_source

    for spec in ("udp://:0", "mavlink:udpin::0"):
        source = open_source(spec)
        try:
            transport = getattr(source, "transport", source)
            assert transport.local_address[0] == "127.0.0.1", spec
        finally:
            source.close()


def test_udp_source_locks_to_its_bridge_and_a_spoofer_neither_rescales_nor_receives(tmp_path):
    """Another process on the machine sends junk first, then a forged CONFIG (16 g instead of 4 g): it is
    counted and ignored; the data keeps its scale, uplink goes to the bridge only, the recording holds
    the bridge's bytes alone."""
    import socket

    import numpy as np

    from firmware_protocol import StreamDecoder
    from firmware_protocol.codec import encode, make_frame

    session = open_session("udp://127.0.0.1:0", filters=("ahf",), recordings_dir=tmp_path)
    target = session.source.local_address
    spoofer = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    spoofer.bind(("127.0.0.1", 0))
    spoofer.settimeout(0.2)
    bridge = UdpBridge(target)
    try:
        with session:
            spoofer.sendto(b"\x00 not a frame " * 8, target)  # before the bridge: no valid frame, no lock
            bridge.start()
            wait_for(lambda: len(session.pipeline.imu) > 100)
            real = next(f for f in StreamDecoder().feed(bytes(bridge.sent)) if f.name == "CONFIG")
            forged = make_frame("CONFIG", real.seq, **{**real.values, "accel_fs_g": 16})
            for _ in range(5):
                spoofer.sendto(encode(forged), target)
            wait_for(lambda: session.source.ignored.datagrams >= 6)
            rows = len(session.pipeline.imu)
            wait_for(lambda: len(session.pipeline.imu) > rows + 100)
            seq = session.send_command("request_config")
            wait_for(lambda: acked(session, seq))
            bridge.close()
            wait_for(lambda: session.pipeline.decoder.stats.bytes_in >= len(bridge.sent), what="the last datagrams in flight")
        with session.lock:
            acc = np.column_stack([session.pipeline.imu.column(f"acc_{c}_g") for c in "xyz"])[-100:]
        assert abs(np.median(np.linalg.norm(acc, axis=1)) - 1.0) < 0.25  # a hover near 1 g; the forged scale gives 4 g
        assert session.source.ignored.senders == [spoofer.getsockname()]
        try:
            leaked = spoofer.recv(4096)
        except TimeoutError:
            leaked = b""
        assert leaked == b""  # no uplink command reached the spoofer
        recording = open_recording(session.recording_path)
        assert b"".join(data for _, data in recording.chunks()) == bytes(bridge.sent)
    finally:
        bridge.close()
        spoofer.close()


def _connections_that_open_late(monkeypatch):
    """``socket.create_connection`` that returns only once the peer's first bytes have arrived: the
    bridge sends as soon as it accepts, and on a loaded machine (or a slow link's RTT after a
    preempted reader) those bytes are there before the source has finished opening."""
    import select
    import socket

    connect = socket.create_connection

    def late(*args, **kwargs):
        sock = connect(*args, **kwargs)
        assert select.select([sock], [], [], LIMIT_S)[0], "the bridge sent nothing"
        return sock

    monkeypatch.setattr(socket, "create_connection", late)


def _serve(payloads: list[bytes]):
    """A bridge that, for each connection in turn, sends its payload on accepting and closes at once (its
    last data and its FIN arrive together)."""
    import socket
    import threading

    server = socket.create_server(("127.0.0.1", 0))

    def serve():
        for payload in payloads:
            client, _ = server.accept()
            with client:
                client.sendall(payload)
                client.shutdown(socket.SHUT_WR)
                while client.recv(4096):  # unread bytes at close would make it a reset: read until the source closes
                    pass

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return server, thread


def read_until_dropped(source) -> list[bytes]:
    import time

    from groundstation.sources import SourceError

    chunks = []
    deadline = time.monotonic() + LIMIT_S
    while True:
        assert time.monotonic() < deadline, "the bridge's close: not seen"
        try:
            chunk = source.read()
        except SourceError:
            return chunks
        if chunk is not None:
            chunks.append(chunk.data)


def test_tcp_source_keeps_the_bytes_that_arrive_while_it_connects_and_those_that_come_with_the_close(monkeypatch):
    """The bytes a bridge sends the moment it accepts, and its last bytes arriving together with its FIN,
    all reach the session, on the first connection and on a reconnection, in a few chunks (not one per byte)."""
    import random

    from groundstation.sources import open_source

    _connections_that_open_late(monkeypatch)
    payloads = [random.Random(seed).randbytes(4096) for seed in (1, 2)]
    server, thread = _serve(payloads)
    try:
        source = open_source(f"tcp://127.0.0.1:{server.getsockname()[1]}")
        first = read_until_dropped(source)
        source.reopen()  # as the session does after the bridge dropped the connection
        second = read_until_dropped(source)
        source.close()
        thread.join(timeout=LIMIT_S)
    finally:
        server.close()
    assert [b"".join(first), b"".join(second)] == payloads
    assert len(first) <= 8 and len(second) <= 8  # what arrived together is read together

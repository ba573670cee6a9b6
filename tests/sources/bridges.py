"""Wi-Fi bridges as the tests' other end: the simulated aircraft's bytes over real sockets on 127.0.0.1.

Each runs a ``SimStream`` in real time in a thread, sends what falls due, and feeds whatever comes
back (uplink) to the simulated firmware, which answers with ACKs as the flight board does.
"""

from __future__ import annotations

import select
import socket
import threading
import time

from groundstation.sim.stream import Scenario, SimStream
from tests.waiting import LIMIT_S

SCENARIO = Scenario("hover", 60.0, seed=7)


class _Pump:
    def __init__(self, scenario: Scenario = SCENARIO):
        self.stream = SimStream(scenario)
        self.sent = bytearray()
        self.uplink = bytearray()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def start(self):
        self.thread.start()
        return self

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5)

    def _received(self, data: bytes) -> None:
        self.uplink += data
        self.stream.receive(data)


class UdpBridge(_Pump):
    """Sends datagrams to ``target``; listens for uplink on its own ephemeral port."""

    def __init__(self, target: tuple[str, int], scenario: Scenario = SCENARIO):
        super().__init__(scenario)
        self.target = target
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind(("127.0.0.1", 0))
        self.socket.settimeout(0.01)

    def _run(self) -> None:
        t0 = time.monotonic()
        while not self.stop.is_set():
            for chunk in self.stream.advance(time.monotonic() - t0):
                self.socket.sendto(chunk.data, self.target)
                self.sent += chunk.data
            try:
                self._received(self.socket.recv(4096))
            except TimeoutError:
                pass
        self.socket.close()


class TcpBridge(_Pump):
    """Serves the stream to one client at a time on 127.0.0.1:``port``; ``drop()`` closes the
    connection (a bridge that rebooted) and the next client continues the same stream."""

    def __init__(self, scenario: Scenario = SCENARIO):
        super().__init__(scenario)
        self.server = socket.create_server(("127.0.0.1", 0))
        self.server.settimeout(0.05)
        self.port = self.server.getsockname()[1]
        self.connections = 0
        self._drop = threading.Event()

    def drop(self) -> None:
        self._drop.set()

    def _run(self) -> None:
        t0 = time.monotonic()
        while not self.stop.is_set():
            try:
                client, _ = self.server.accept()
            except TimeoutError:
                self.stream.advance(time.monotonic() - t0)  # nobody listening: those bytes are lost
                continue
            self.connections += 1
            client.settimeout(LIMIT_S)
            with client:
                while not self.stop.is_set() and not self._drop.is_set():
                    for chunk in self.stream.advance(time.monotonic() - t0):
                        client.sendall(chunk.data)
                        self.sent += chunk.data
                    if not select.select([client], [], [], 0.01)[0]:  # the pace of the stream, not a wait for an outcome
                        continue
                    data = client.recv(4096)
                    if not data:
                        break
                    self._received(data)
                _close_gently(client)
            self._drop.clear()
        self.server.close()


def _close_gently(client: socket.socket) -> None:
    """A FIN after the last bytes, then the peer's bytes drained until it closes too (the session does
    when it reads the end): closing with unread bytes sends a reset, and the reset discards what this
    side had not yet delivered."""
    try:
        client.shutdown(socket.SHUT_WR)
        while client.recv(4096):
            pass
    except OSError:  # a reset from the peer, or LIMIT_S without its close: nothing more to keep
        return

"""The simulated stream sent over UDP in real time, as ArduPilot SITL and Wi-Fi telemetry bridges send
MAVLink: datagrams to ``target`` (a ground station listening with ``mavlink:udpin:0.0.0.0:PORT``), and
whatever comes back on the same socket is the uplink. Datagrams to nobody are lost, as on a real link.
"""

from __future__ import annotations

import select
import socket
import time


class UdpBridge:
    def __init__(self, stream, target: tuple[str, int]):
        self.stream = stream
        self.target = target
        self.datagrams = 0
        self.bytes_written = 0
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.bind(("0.0.0.0", 0))

    @property
    def path(self) -> str:
        return f"udp {self.target[0]}:{self.target[1]}"

    def run(self, should_stop, duration_s: float | None = None) -> None:
        """Stream in real time until ``should_stop()`` is true or ``duration_s`` has passed."""
        t0 = time.monotonic()
        while not should_stop():
            now = time.monotonic() - t0
            if duration_s is not None and now >= duration_s:
                break
            for chunk in self.stream.advance(now):
                try:
                    self.bytes_written += self._socket.sendto(chunk.data, self.target)
                    self.datagrams += 1
                except OSError:
                    pass  # nobody listening (ICMP unreachable): the datagram is lost
            timeout = min(max(self.stream.next_event_s() - (time.monotonic() - t0), 0.0), 0.05)
            readable, _, _ = select.select([self._socket], [], [], timeout)
            if readable:
                try:
                    self.stream.receive(self._socket.recv(65_535))
                except OSError:
                    pass  # an earlier datagram's ICMP error surfaces here; nothing to read

    def close(self) -> None:
        self._socket.close()

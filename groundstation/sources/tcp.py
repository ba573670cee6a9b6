"""``tcp://HOST:PORT``: a TCP bridge (an ESP32 or other Wi-Fi serial bridge serving the radio's bytes).

The ground station connects to HOST:PORT; uplink goes back on the same connection. When the bridge
drops the connection (it rebooted, Wi-Fi faded) the session reconnects as it does for an unplugged
USB adapter.

A plain socket, not pyserial's ``socket://`` handler: that handler empties the receive buffer at
every open, so the bytes a bridge sends the moment it accepts (the stream's start, its CONFIG) were
dropped whenever they arrived before the open had finished (a loaded machine, a reconnection); and it
reads one byte per call, one chunk per byte. Here each read takes whatever has arrived, and the last
bytes before the bridge's close are read before the close is reported.
"""

from __future__ import annotations

import select
import socket
import time

from groundstation.sources.base import Chunk, SourceError

READ_TIMEOUT_S = 0.05  # the reader's longest wait: it notices a stop request this quickly
CONNECT_TIMEOUT_S = 5.0  # a bridge that does not answer: the session tries again (every 0.5 s)
SEND_TIMEOUT_S = 5.0  # a bridge that stopped reading: the command fails with a warning instead of hanging the caller
MAX_READ_BYTES = 65536


class TcpSource:
    is_replay = False
    can_reopen = True
    can_send = True

    def __init__(self, host: str, port: int, description: str):
        self.address = (host, port)
        self.description = description
        self._socket = self._connect()

    def _connect(self) -> socket.socket:
        try:
            sock = socket.create_connection(self.address, timeout=CONNECT_TIMEOUT_S)
        except (OSError, UnicodeError) as error:
            reason = f"[Errno {error.errno}] {error.strerror}" if getattr(error, "errno", None) else error
            raise SourceError(f"cannot open the {self.description}: {reason}") from None
        sock.settimeout(SEND_TIMEOUT_S)  # reads wait in select (READ_TIMEOUT_S), never in recv
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)  # a command goes out at once, not with the next
        return sock

    def read(self) -> Chunk | None:
        sock = self._socket
        try:
            if not select.select([sock], [], [], READ_TIMEOUT_S)[0]:
                return None
            data = sock.recv(MAX_READ_BYTES)
        except (OSError, ValueError) as error:  # ValueError: closed by another thread meanwhile
            raise SourceError(f"{self.description}: the connection failed ({error})") from None
        if not data:  # everything before the bridge's close was read by the earlier calls
            raise SourceError(f"{self.description}: the bridge closed the connection")
        return Chunk(time.monotonic_ns(), data)

    def write(self, data: bytes) -> None:
        try:
            self._socket.sendall(data)
        except OSError as error:
            raise SourceError(f"{self.description}: cannot send ({error})") from None

    def reopen(self) -> None:
        """Connect again after the bridge dropped the connection."""
        self.close()
        self._socket = self._connect()

    def close(self) -> None:
        self._socket.close()


def open_spec(spec) -> TcpSource:
    spec.check_options(())
    host, port = spec.host_port()
    host = host or "localhost"
    address = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"  # an IPv6 address keeps its brackets
    return TcpSource(host, port, f"TCP bridge {address}")

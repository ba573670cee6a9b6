"""``udp://HOST:PORT``: a UDP bridge (an ESP32 or other Wi-Fi bridge sending the radio's bytes as datagrams).

The ground station *listens* on HOST:PORT (``0.0.0.0`` or an empty host: every interface) and each
datagram is one chunk, stamped on arrival. Uplink goes back to the address the last datagram came
from; commands written before any datagram arrived are held (a few) and sent to the first sender,
unless ``?remote=HOST:PORT`` names where the bridge listens (for bridges that wait to be spoken to).
"""

from __future__ import annotations

import socket
import threading
import time

from groundstation.sources.base import Chunk, SourceError
from groundstation.sources.spec import Spec

READ_TIMEOUT_S = 0.05
MAX_DATAGRAM_BYTES = 65535
HELD_WRITES = 16  # uplink frames kept until the bridge's address is known


class UdpSource:
    is_replay = False
    can_reopen = True  # rebinding helps after a network interface went down and came back
    can_send = True

    def __init__(self, host: str, port: int, remote: tuple[str, int] | None = None):
        self.address = (host, port)
        self.description = f"UDP bridge on {host or '0.0.0.0'}:{port}"
        self._remote = remote and _resolve(*remote, self.description)
        self._peer = self._remote
        self._held: list[bytes] = []
        self._lock = threading.Lock()
        self._socket = self._bind()

    def _bind(self) -> socket.socket:
        family, address = _resolve(*self.address, self.description, passive=True)
        sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            sock.bind(address)
        except OSError as error:
            sock.close()
            raise SourceError(f"{self.description}: cannot listen ({error.strerror or error}); "
                              "another program (another ground station?) may be using the port") from None
        sock.settimeout(READ_TIMEOUT_S)
        return sock

    @property
    def local_address(self) -> tuple[str, int]:
        """Where it listens (the port the system chose, when asked for port 0)."""
        return self._socket.getsockname()[:2]

    def read(self) -> Chunk | None:
        try:
            data, sender = self._socket.recvfrom(MAX_DATAGRAM_BYTES)
        except TimeoutError:
            return None
        except ConnectionResetError:
            return None  # Windows reports an earlier send's ICMP "port unreachable" here: not our stream's end
        except OSError as error:
            raise SourceError(f"{self.description}: receiving failed ({error.strerror or error})") from None
        t_host_ns = time.monotonic_ns()
        with self._lock:
            first = self._peer is None
            if self._remote is None:
                self._peer = sender
            held, self._held = self._held, []
        if first:
            for data_held in held:
                self._send(data_held)
        return Chunk(t_host_ns, data) if data else None

    def write(self, data: bytes) -> None:
        with self._lock:
            if self._peer is None:
                self._held = [*self._held, bytes(data)][-HELD_WRITES:]
                return
        self._send(data)

    def _send(self, data: bytes) -> None:
        try:
            self._socket.sendto(data, self._peer)
        except OSError as error:
            raise SourceError(f"{self.description}: cannot send to {self._peer[0]}:{self._peer[1]} "
                              f"({error.strerror or error})") from None

    def reopen(self) -> None:
        self.close()
        self._socket = self._bind()

    def close(self) -> None:
        self._socket.close()


def _resolve(host: str, port: int, what: str, passive: bool = False) -> tuple:
    """(family, sockaddr) for HOST:PORT, or for listening on every interface when ``host`` is empty."""
    try:
        info = socket.getaddrinfo(host or None, port, type=socket.SOCK_DGRAM, flags=socket.AI_PASSIVE if passive else 0)
    except (socket.gaierror, UnicodeError) as error:
        raise SourceError(f"{what}: unknown host {host!r} ({error})") from None
    family, _, _, _, address = info[0]
    return (family, address) if passive else address


def open_spec(spec) -> UdpSource:
    spec.check_options({"remote"})
    host, port = spec.host_port()
    remote = Spec(spec.text, "udp", spec.options["remote"]).host_port() if "remote" in spec.options else None
    return UdpSource(host, port, remote)

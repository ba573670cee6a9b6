"""``udp://HOST:PORT``: a UDP bridge (an ESP32 or other Wi-Fi bridge sending the radio's bytes as datagrams).

The ground station *listens* on HOST:PORT: on this machine only (127.0.0.1) when no host is named, on
every interface only when asked (``0.0.0.0``), and each datagram is one chunk, stamped on arrival.

Trust comes from configuration, not from arrival: the source locks to one sender, the one
``?remote=HOST:PORT`` names (for bridges that wait to be spoken to), else the first whose datagram
carries a valid frame of the link's protocol (its checksum intact, ``admits``); datagrams from every
other address are dropped and counted (``ignored``), never recorded or decoded. Uplink goes only to
the locked sender; commands written before it is known are held (a few) and sent to it then. Why the
first valid frame and not the first CONFIG: a bridge that started before the ground station sent its
CONFIG already, and asking for it again needs a sender to ask.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from groundstation.sources.base import Chunk, SourceError
from groundstation.sources.sniff import SNIFF_BYTES
from groundstation.sources.spec import Spec

READ_TIMEOUT_S = 0.05
MAX_DATAGRAM_BYTES = 65535
HELD_WRITES = 16  # uplink frames kept until the bridge's address is known
LOCAL_HOST = "127.0.0.1"  # where an address without a host listens
NAMED_SENDERS = 16  # other senders named in the report; the count goes on past them


@dataclass
class Ignored:
    """Datagrams from senders other than the locked one: counted, and the first few senders named."""

    datagrams: int = 0
    senders: list = field(default_factory=list)

    def add(self, sender) -> None:
        self.datagrams += 1
        if sender not in self.senders and len(self.senders) < NAMED_SENDERS:
            self.senders.append(sender)

    def __str__(self) -> str:
        named = ", ".join(f"{host}:{port}" for host, port, *_ in self.senders)
        return f"ignored {self.datagrams} datagrams from other senders ({named})"


def carries_a_frame(data: bytes) -> bool:
    """Whether a datagram holds a whole frame of this project's protocol with its checksum intact."""
    from firmware_protocol import StreamDecoder

    return bool(StreamDecoder().feed(data))


class UdpSource:
    is_replay = False
    can_reopen = True  # rebinding helps after a network interface went down and came back
    can_send = True

    def __init__(self, host: str, port: int, remote: tuple[str, int] | None = None,
                 admits: Callable[[bytes], bool] = carries_a_frame):
        host = host or LOCAL_HOST
        self.address = (host, port)
        self.description = f"UDP bridge on {host}:{port}"
        self._admits = admits
        self._remote = remote and _resolve(*remote, self.description)
        self._peer = self._remote
        self.ignored = Ignored()
        self.refused = bytearray()  # the first datagrams refused before a sender was locked: what do they speak (``sniff``)?
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
            if first and data and self._admits(data):
                self._peer = sender
            elif first and len(self.refused) < SNIFF_BYTES:
                self.refused += data[: SNIFF_BYTES - len(self.refused)]
            if sender != self._peer:
                self.ignored.add(sender)
                return None
            held, self._held = (self._held, []) if first else ([], self._held)
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

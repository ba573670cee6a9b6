"""MAVLink sources: ``open_mavlink("mavlink:...")`` for the ``mavlink:`` scheme of ``open_source``.

| spec | what |
|---|---|
| ``mavlink:/dev/ttyUSB0?baud=57600``, ``mavlink:COM4`` | a serial port (SiK telemetry radios: 57600, the default) |
| ``mavlink:udpin:0.0.0.0:14550`` | listen on UDP (SITL, Wi-Fi bridges; port 0: any free one); uplink goes to whoever sent last |
| ``mavlink:udpout:192.168.4.1:14550`` | send to a UDP address and read its answers |
| ``mavlink:tcp:127.0.0.1:5760`` | a TCP connection (ArduPilot SITL's serial 0) |
| ``mavlink:flight.tlog?speed=4`` | a ``.tlog`` replayed, as fast as possible or at 0.25x-64x |

Every source yields the raw bytes stamped on arrival (``Chunk``): what a session records. Decoding is
``groundstation.autopilot.decoder.MavlinkDecoder``; ``protocol = "mavlink"`` tells the pipeline which.
"""

from __future__ import annotations

import select
import socket
import time
from pathlib import Path
from urllib.parse import parse_qs

from groundstation.sources.base import Chunk, SourceClosed, SourceError
from groundstation.sources.serial_port import SerialSource

SCHEME = "mavlink:"
SIK_BAUD = 57600
READ_WAIT_S = 0.05
MAX_DATAGRAM = 65_535
MIN_SPEED, MAX_SPEED = 0.25, 64.0


def open_mavlink(spec: str):
    """The source a ``mavlink:`` string names; SourceError with a clear message otherwise."""
    if not spec.startswith(SCHEME):
        raise SourceError(f"{spec!r} is not a MAVLink source (it should start with {SCHEME!r})")
    target, _, query = spec[len(SCHEME):].partition("?")
    options = {k: v[-1] for k, v in parse_qs(query).items()}
    kind, _, address = target.partition(":")
    if kind in ("udpin", "udpout", "tcp"):
        host, port = split_address(address, spec)
        return UdpSource(host, port, listen=kind == "udpin") if kind != "tcp" else TcpSource(host, port)
    if target.lower().endswith(".tlog"):
        return TlogReplaySource(target, number(options.get("speed"), spec) if "speed" in options else None)
    if not target:
        raise SourceError(f"{spec!r}: name a serial port, udpin:, udpout:, tcp: or a .tlog file after 'mavlink:'")
    return MavlinkSerialSource(target, int(number(options.get("baud", SIK_BAUD), spec)))


def split_address(address: str, spec: str) -> tuple[str, int]:
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit() or not 0 <= int(port) < 65536:
        raise SourceError(f"{spec!r}: expected HOST:PORT, e.g. mavlink:udpin:0.0.0.0:14550")
    return host, int(port)


def number(text, spec: str) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        raise SourceError(f"{spec!r}: {text!r} is not a number") from None


class MavlinkSerialSource(SerialSource):
    protocol = "mavlink"
    is_replay = False
    can_reopen = True
    can_send = True

    def __init__(self, port: str, baud: int = SIK_BAUD):
        super().__init__(port, baud)
        self.description = f"MAVLink on {port} @ {baud} baud"


class UdpSource:
    """``listen``: bound to (host, port), answering the last sender; else sending to (host, port)."""

    protocol = "mavlink"
    is_replay = False
    can_reopen = False
    can_send = True

    def __init__(self, host: str, port: int, listen: bool):
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            if listen:
                self._socket.bind((host, port))
            else:
                self._socket.connect((host, port))  # a local port is chosen; the peer answers to it
        except OSError as error:
            self._socket.close()
            raise SourceError(f"cannot {'listen on' if listen else 'reach'} UDP {host}:{port}: {error.strerror or error}") from None
        self._peer = None if listen else (host, port)
        self.description = f"MAVLink UDP {'in' if listen else 'out'} {host}:{self.port if listen else port}"

    @property
    def port(self) -> int:
        """The local port (useful when bound to port 0)."""
        return self._socket.getsockname()[1]

    def read(self) -> Chunk | None:
        try:
            readable, _, _ = select.select([self._socket], [], [], READ_WAIT_S)
            if not readable:
                return None
            data, peer = self._socket.recvfrom(MAX_DATAGRAM)
        except ConnectionRefusedError:
            return None  # udpout before the peer listens: ICMP port unreachable; keep trying
        except OSError as error:
            raise SourceError(f"{self.description}: {error.strerror or error}") from None
        self._peer = peer
        return Chunk(time.monotonic_ns(), data)

    def write(self, data: bytes) -> None:
        if self._peer is None:
            return  # udpin before anyone has sent: nobody to answer yet
        try:
            self._socket.sendto(data, self._peer)
        except OSError as error:
            raise SourceError(f"{self.description}: cannot send ({error.strerror or error})") from None

    def reopen(self) -> None:
        raise SourceError(f"{self.description} cannot be reopened")

    def close(self) -> None:
        self._socket.close()


class TcpSource:
    protocol = "mavlink"
    is_replay = False
    can_reopen = True
    can_send = True

    def __init__(self, host: str, port: int):
        self.host, self.port = host, port
        self.description = f"MAVLink TCP {host}:{port}"
        self._socket = self._connect()

    def _connect(self) -> socket.socket:
        try:
            return socket.create_connection((self.host, self.port), timeout=2.0)
        except OSError as error:
            raise SourceError(f"cannot connect to TCP {self.host}:{self.port}: {error.strerror or error}") from None

    def read(self) -> Chunk | None:
        try:
            readable, _, _ = select.select([self._socket], [], [], READ_WAIT_S)
            if not readable:
                return None
            data = self._socket.recv(MAX_DATAGRAM)
        except OSError as error:
            raise SourceError(f"{self.description}: {error.strerror or error}") from None
        if not data:
            raise SourceError(f"{self.description}: the other end closed the connection")
        return Chunk(time.monotonic_ns(), data)

    def write(self, data: bytes) -> None:
        try:
            self._socket.sendall(data)
        except OSError as error:
            raise SourceError(f"{self.description}: cannot send ({error.strerror or error})") from None

    def reopen(self) -> None:
        self.close()
        self._socket = self._connect()

    def close(self) -> None:
        self._socket.close()


class TlogReplaySource:
    """A ``.tlog`` as a source: one chunk per packet, stamped with its recorded receive time (ns)."""

    protocol = "mavlink"
    is_replay = True
    can_reopen = False
    can_send = False

    def __init__(self, path, speed: float | None = None):
        from groundstation.autopilot.tlog import packets

        path = Path(path)
        try:
            data = path.read_bytes()
        except OSError as error:
            raise SourceError(f"cannot open {path}: {error.strerror}") from None
        if speed is not None and not MIN_SPEED <= speed <= MAX_SPEED:
            raise SourceError(f"replay speed must be between {MIN_SPEED}x and {MAX_SPEED}x, not {speed}x")
        self._packets = [(stamp_us * 1000, packet) for stamp_us, packet in packets(data) if packet is not None]
        if not self._packets:
            raise SourceError(f"{path}: no MAVLink packets found; not a .tlog?")
        self.description = f"replay of {path.name}"
        self.speed = speed
        self._index = 0
        self._wall0 = None

    def read(self) -> Chunk | None:
        if self._index >= len(self._packets):
            raise SourceClosed(self.description)
        t_ns, packet = self._packets[self._index]
        if self.speed is not None:
            if self._wall0 is None:
                self._wall0 = time.monotonic_ns()
            wait_s = (self._wall0 + (t_ns - self._packets[0][0]) / self.speed - time.monotonic_ns()) / 1e9
            if wait_s > 0:
                time.sleep(min(wait_s, READ_WAIT_S))
                return None
        self._index += 1
        return Chunk(t_ns, bytes(packet))

    def write(self, data: bytes) -> None:
        """A log has no aircraft to command: uplink bytes are dropped."""

    def reopen(self) -> None:
        raise SourceError(f"{self.description} cannot be reopened")

    def close(self) -> None:
        self._index = len(self._packets)

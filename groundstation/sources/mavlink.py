"""``mavlink:``: an autopilot speaking MAVLink 1 or 2 (ArduPilot, PX4), over any of the byte transports.

| spec | what |
|---|---|
| ``mavlink:/dev/ttyUSB0[?baud=N]``, ``mavlink:COM4`` | a serial port: a SiK telemetry radio (57600, the default here) or a USB autopilot |
| ``mavlink:udpin:0.0.0.0:14550`` | listen on UDP (SITL, Wi-Fi bridges; port 0: any free one; no host: this machine only); locked to the first sender of a valid packet, uplink to it alone |
| ``mavlink:udpout:192.168.4.1:14550`` | send to that address first (a GCS heartbeat, so it learns ours) and read its answers |
| ``mavlink:tcp:127.0.0.1:5760`` | a TCP connection (ArduPilot SITL's first serial port) |
| ``mavlink:flight.tlog[?speed=X]`` | a ``.tlog`` replayed, packet by packet at its receive times (X: 0.25-64, or max) |

On a live link ``?system=N`` (1-255) picks the vehicle: the autopilot with that MAVLink system id, whatever
else is heard first (another vehicle, a spoofer); without it, the first autopilot heard is the vehicle.

The transports are the generic ones (``serial_port``, ``udp``); ``MavlinkSource`` hands over their bytes
unchanged, stamped on arrival (what a session records), and says ``protocol = "mavlink"`` so the
session decodes them with ``groundstation.autopilot.decoder.MavlinkDecoder``.
"""

from __future__ import annotations

import time
from pathlib import Path

from groundstation.sources.base import Chunk, SourceClosed, SourceError
from groundstation.sources.serial_port import SerialSource
from groundstation.sources.spec import Spec
from groundstation.sources.tcp import TcpSource
from groundstation.sources.udp import UdpSource

SIK_BAUD = 57600
READ_WAIT_S = 0.05
MIN_SPEED, MAX_SPEED = 0.25, 64.0


class MavlinkSource:
    """A transport carrying MAVLink: its capabilities, reads and writes, labelled for the decoder."""

    protocol = "mavlink"

    def __init__(self, transport, description: str, vehicle_system: int | None = None):
        self.transport = transport
        self.description = description
        self.vehicle_system = vehicle_system  # the system id picked as the vehicle (``?system=N``); None: the first heard
        self.is_replay = transport.is_replay
        self.can_reopen = transport.can_reopen
        self.can_send = transport.can_send
        self.ignored = getattr(transport, "ignored", None)  # a UDP transport's datagrams from other senders

    def read(self) -> Chunk | None:
        return self.transport.read()

    def write(self, data: bytes) -> None:
        self.transport.write(data)

    def reopen(self) -> None:
        self.transport.reopen()

    def close(self) -> None:
        self.transport.close()


def carries_mavlink(data: bytes) -> bool:
    """Whether a datagram holds a whole MAVLink packet with its checksum intact."""
    from groundstation.autopilot.decoder import new_parser

    return any(msg.get_type() != "BAD_DATA" for msg in new_parser().parse_buffer(data) or ())


def open_spec(spec: Spec) -> MavlinkSource:
    kind, _, address = spec.target.partition(":")
    if spec.target.lower().endswith(".tlog"):
        spec.check_options({"speed"})
        speed = spec.option("speed", lambda text: None if text == "max" else float(text), None)
        return MavlinkSource(TlogReplaySource(spec.target, speed), f"MAVLink replay of {Path(spec.target).name}")
    system = spec.option("system", system_id, None)  # checked before a port or socket is opened
    source = open_link(spec, kind, address)
    source.vehicle_system = system
    return source


def system_id(text: str) -> int:
    from groundstation.autopilot.vehicle import MAX_SYSTEM, MIN_SYSTEM

    system = int(text)
    if not MIN_SYSTEM <= system <= MAX_SYSTEM:
        raise ValueError(f"a MAVLink system id is {MIN_SYSTEM} to {MAX_SYSTEM}")
    return system


def open_link(spec: Spec, kind: str, address: str) -> MavlinkSource:
    if kind in ("udpin", "udpout", "tcp"):
        spec.check_options({"system"})
        host, port = Spec(spec.text, "udp", address).host_port()
        if kind == "udpin":
            transport = UdpSource(host, port, admits=carries_mavlink)
            return MavlinkSource(transport, f"MAVLink UDP in {transport.address[0]}:{port}")
        if kind == "tcp":
            host = host or "localhost"
            return MavlinkSource(TcpSource(host, port, f"MAVLink TCP {host}:{port}"), f"MAVLink TCP {host}:{port}")
        from groundstation.autopilot.streams import gcs_heartbeat

        # Every interface: the vehicle may be on another machine; only its address is trusted (remote).
        source = MavlinkSource(UdpSource("0.0.0.0", 0, remote=(host, port)), f"MAVLink UDP out {host}:{port}")
        source.write(gcs_heartbeat())  # the vehicle answers whoever spoke to it
        return source
    if not spec.target:
        raise SourceError(f"{spec.text}: name a serial port, udpin:, udpout:, tcp: or a .tlog file after 'mavlink:'")
    spec.check_options({"baud", "system"})
    baud = spec.option("baud", int, SIK_BAUD)  # ?baud=, else the app's baud box or --baud, else a SiK radio's rate
    return MavlinkSource(SerialSource(spec.target, baud), f"MAVLink on {spec.target} @ {baud} baud")


class TlogReplaySource:
    """A ``.tlog`` as a source: one chunk per packet, stamped with its receive time (ns) as a session
    opening the file takes it (``autopilot.tlog.session_packets``: a compressed log on the autopilot's clock)."""

    is_replay = True
    can_reopen = False
    can_send = False

    def __init__(self, path, speed: float | None = None):
        from groundstation.autopilot.tlog import session_packets

        path = Path(path)
        try:
            data = path.read_bytes()
        except OSError as error:
            raise SourceError(f"cannot open {path}: {error.strerror}") from None
        if speed is not None and not MIN_SPEED <= speed <= MAX_SPEED:
            raise SourceError(f"replay speed must be between {MIN_SPEED}x and {MAX_SPEED}x, not {speed}x")
        self._packets = session_packets(data).packets
        if not self._packets:
            raise SourceError(f"{path}: no MAVLink packets found; not a .tlog?")
        self.description = f"replay of {path.name}"
        self.speed = speed
        self._index = 0
        self._wall0: int | None = None

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

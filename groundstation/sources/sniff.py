"""What a stream speaks when it is not what the session expected: an autopilot's MAVLink on a source
opened for the project's bridge (``udp://0.0.0.0:14550``, a SiK radio's port typed without ``mavlink:``).

A session on the project's protocol keeps the first ``SNIFF_BYTES`` it reads until a frame of its own
decodes (``ForeignBytes``); a UDP source keeps those of the datagrams it refused before it locked to a
sender (``UdpSource.refused``). They are MAVLink when they hold ``MIN_PACKETS`` whole packets with their
checksums intact (pymavlink's parser, the message's CRC_EXTRA included): one could come about by chance
in a few KB of other bytes (about 1 in 65,536 per 0xFE/0xFD byte), two in a row practically never.
``as_mavlink`` names the ``mavlink:`` source of the same port.
"""

from __future__ import annotations

from groundstation.sources.base import SourceError
from groundstation.sources.spec import parse_spec

SNIFF_BYTES = 4096
MIN_PACKETS = 2


def mavlink_packets(data: bytes) -> int:
    """How many whole MAVLink 1 or 2 packets with intact checksums ``data`` holds."""
    from groundstation.autopilot.decoder import new_parser

    return sum(msg.get_type() != "BAD_DATA" for msg in new_parser().parse_buffer(bytes(data)) or ())


class ForeignBytes:
    """The first bytes of a stream in which no frame of the session's protocol has decoded yet."""

    def __init__(self):
        self._kept = bytearray()
        self._protocol: str | None = None

    def add(self, data: bytes) -> None:
        room = SNIFF_BYTES - len(self._kept)
        if room > 0:
            self._kept += data[:room]

    def protocol(self, more: bytes = b"") -> str | None:
        """"mavlink" once the bytes kept (and ``more``: a UDP source's refused datagrams) hold MAVLink."""
        if self._protocol is None and mavlink_packets(bytes(self._kept)) + mavlink_packets(more) >= MIN_PACKETS:
            self._protocol = "mavlink"
        return self._protocol


def as_mavlink(text: str, baud: int | None = None) -> str | None:
    """The ``mavlink:`` spec for the port ``text`` names: ``udp://H:P`` -> ``mavlink:udpin:H:P``,
    ``tcp://H:P`` -> ``mavlink:tcp:H:P``, a serial port -> ``mavlink:PORT?baud=N`` (its ``?baud=``, else
    ``baud``: the rate the MAVLink was heard at);
    None for a source that is no port (``sim:``, a file) or is MAVLink already."""
    try:
        spec = parse_spec(text)
    except SourceError:
        return None
    if spec.scheme == "udp":
        return f"mavlink:udpin:{spec.target}"
    if spec.scheme == "tcp":
        return f"mavlink:tcp:{spec.target}"
    if spec.scheme == "serial":
        baud = spec.options.get("baud", baud)
        return f"mavlink:{spec.target}" + (f"?baud={baud}" if baud else "")
    return None

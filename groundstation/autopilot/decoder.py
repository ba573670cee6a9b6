"""Raw link bytes -> records: pymavlink's parser (MAVLink 1 and 2, the ardupilotmega dialect, a
superset of common) with ``robust_parsing`` so junk is skipped and counted, then ``MessageMapper``.

Interface for the live pipeline::

    decoder = MavlinkDecoder()
    for chunk in source:                      # raw bytes stamped on arrival
        for record in decoder.feed(chunk.data, chunk.t_host_ns):
            ...                               # records.ImuSample, OnboardAttitude, MagReading, ...
    decoder.stats, decoder.senders            # bytes, messages, bad bytes; per sender received / lost
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega

from groundstation.autopilot.mapping import MessageMapper, SenderCounts


@dataclass
class DecoderStats:
    bytes_in: int = 0
    messages: int = 0
    bad_bytes: int = 0  # bytes that were not part of a valid message (junk, CRC failures, unknown ids)
    bad_runs: int = 0  # how many separate runs of such bytes


def new_parser():
    """A pymavlink parser for incoming bytes (no file: it only parses)."""
    parser = ardupilotmega.MAVLink(None)
    parser.robust_parsing = True
    return parser


class MavlinkDecoder:
    def __init__(self):
        self._parser = new_parser()
        self.mapper = MessageMapper()
        self.stats = DecoderStats()

    @property
    def senders(self) -> dict[tuple[int, int], SenderCounts]:
        return self.mapper.senders

    def messages(self, data: bytes) -> list:
        """The pymavlink messages completed by ``data`` (bad data counted and dropped)."""
        self.stats.bytes_in += len(data)
        out = []
        for msg in self._parser.parse_buffer(data) or ():
            if msg.get_type() == "BAD_DATA":
                self.stats.bad_bytes += len(msg.data)
                self.stats.bad_runs += 1
            else:
                out.append(msg)
        self.stats.messages += len(out)
        return out

    @property
    def idle(self) -> bool:
        """No bytes of an unfinished message wait in the parser: the next packet is parsed on its own."""
        return self._parser.buf_len() == 0

    def feed(self, data: bytes, t_host_ns: int = 0) -> list:
        """Records of every message completed by ``data``, in arrival order."""
        records = []
        for msg in self.messages(data):
            records.extend(self.mapper.map(msg, t_host_ns))
        return records

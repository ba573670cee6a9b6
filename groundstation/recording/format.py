"""The recording file layout (version 1), byte by byte; ``docs/recording-format.md`` is the prose.

    preamble   MAGIC (8 bytes) | format version (uint32)
    record     MARKER (4) | kind (uint8) | payload length (uint32) | t_host_ns (int64)
               | payload | CRC-32 (uint32) of kind..payload

All integers little-endian. The first record is the METADATA record; the last, when the writer
closed cleanly, the END record.
"""

from __future__ import annotations

import enum
import struct
import zlib

from groundstation.errors import UserError

MAGIC = b"\x89GSREC\r\n"  # non-ASCII first byte and CR LF: like PNG, catches text-mode mangling
PREAMBLE = struct.Struct("<8sI")
FORMAT_VERSION = 1  # the newest version this code writes and reads; older ones stay readable
EXTENSION = ".gsrec"

# Not 0xA5 (the telemetry sync byte), so raw link bytes do not look like record starts as often.
MARKER = b"\xf3Rec"
RECORD_HEADER = struct.Struct("<4sBIq")  # marker, kind, payload length, t_host_ns
CRC = struct.Struct("<I")
RECORD_OVERHEAD_BYTES = RECORD_HEADER.size + CRC.size
# A length above this is corruption, not data: the writer splits anything bigger, and the reader
# never trusts a damaged length to swallow the rest of the file.
MAX_PAYLOAD_BYTES = 16 * 1024 * 1024


class Kind(enum.IntEnum):
    METADATA = 1  # payload: UTF-8 JSON object
    CHUNK = 2  # payload: the raw link bytes as received
    EVENT = 3  # payload: UTF-8 JSON object
    SAMPLES = 4  # payload: a block of float64 columns (groundstation.recording.samples)
    END = 5  # payload: empty; written by close()


class RecordingError(UserError):
    """Nothing can be read from the file, or it cannot be written; the message says why."""


def encode_preamble(version: int = FORMAT_VERSION) -> bytes:
    return PREAMBLE.pack(MAGIC, version)


def encode_record(kind: Kind, t_host_ns: int, payload: bytes) -> bytes:
    header = RECORD_HEADER.pack(MARKER, kind, len(payload), t_host_ns)
    crc = zlib.crc32(payload, zlib.crc32(header[len(MARKER):]))
    return b"".join((header, payload, CRC.pack(crc)))

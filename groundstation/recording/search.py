"""Finding intact records in damaged bytes in time linear in the file size, whatever the bytes are.

Checking one candidate record (a MARKER) costs a CRC over its declared length, up to
``MAX_PAYLOAD_BYTES``; a file made of false headers that each declare a long payload would make a
candidate-by-candidate search quadratic (17.8 MB of them took over a minute). Instead the bytes of a
window are hashed once, the running CRC is kept at each candidate's start and end, and each
candidate's own CRC follows from those two by CRC-32's linearity (zlib's ``crc32_combine``):

    crc(A + B) = crc(A) * x^(8 |B|)  mod P   xor   crc(B)

so ``crc(B) = crc(A + B) xor crc(A) * x^(8 |B|)``, where multiplying by ``x^(8 n)`` is a product of
the constants ``x^(8 * 2^k)`` for the bits of ``n``; each constant's product is linear in the other
factor and done by four byte-table lookups, for all candidates of a window at once.
"""

from __future__ import annotations

import functools
import zlib

import numpy as np

from groundstation.recording.format import CRC, MARKER, MAX_PAYLOAD_BYTES, RECORD_HEADER

HEADER_BYTES = RECORD_HEADER.size
MARKER_BYTES = len(MARKER)
LENGTH_AT = MARKER_BYTES + 1  # the payload length field follows the marker and the kind byte
POLY = 0xEDB88320  # CRC-32 (zlib), reflected: bit 31 is x^0
# A record's CRC covers kind..payload: at most this many bytes, so these many bits of a length.
LENGTH_BITS = (HEADER_BYTES - MARKER_BYTES + MAX_PAYLOAD_BYTES).bit_length()
# The bytes searched per window: the work per window is this plus one longest record, and the
# candidate arrays hold at most one entry per HEADER_BYTES of it.
WINDOW_BYTES = 4 * 1024 * 1024
PLACES_AT_ONCE = 65536


def _multiply(a: int, b: int) -> int:
    """a * b modulo P in CRC-32's reflected bit order (zlib's multmodp)."""
    product, mask = 0, 1 << 31
    while mask:
        if a & mask:
            product ^= b
        mask >>= 1
        b = (b >> 1) ^ POLY if b & 1 else b >> 1
    return product


@functools.cache
def _shift_tables() -> np.ndarray:
    """tables[k, j, byte]: (byte << 8 j) * x^(8 * 2^k) mod P, for k below LENGTH_BITS."""
    tables = np.zeros((LENGTH_BITS, 4, 256), dtype=np.uint32)
    byte_values = np.arange(256, dtype=np.uint32)
    constant = 1 << 23  # x^8 (x^0 is bit 31)
    for k in range(LENGTH_BITS):
        for j in range(4):
            for bit in range(8):
                column = _multiply(constant, 1 << (8 * j + bit))
                tables[k, j] ^= np.where(byte_values >> bit & 1, np.uint32(column), np.uint32(0))
        constant = _multiply(constant, constant)
    return tables


def _shift(crcs: np.ndarray, n_bytes: np.ndarray) -> np.ndarray:
    """Each crc times x^(8 n) mod P: what it becomes when n bytes follow (zlib's crc32_combine)."""
    tables = _shift_tables()
    crcs = crcs.copy()
    for k in range(LENGTH_BITS):
        take = (n_bytes >> k & 1).astype(bool)
        v = crcs[take]
        t = tables[k]
        crcs[take] = t[0][v & 0xFF] ^ t[1][v >> 8 & 0xFF] ^ t[2][v >> 16 & 0xFF] ^ t[3][v >> 24]
    return crcs


def _gather_uint32(data: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The little-endian uint32 at each offset ``at`` of ``data`` (uint8)."""
    value = np.zeros(len(at), dtype=np.uint32)
    for i in range(4):
        value |= data[at + i].astype(np.uint32) << np.uint32(8 * i)
    return value


def intact_records(buffer, start: int, stop: int) -> tuple[np.ndarray, int]:
    """(sorted starts of the intact records beginning in [start, stop'), stop') with stop' >= min(stop, end):

    a record is intact when its marker, its length (at most ``MAX_PAYLOAD_BYTES``, inside the file)
    and its CRC agree. ``stop'`` is where the window searched ended (at most WINDOW_BYTES on from ``start``).
    """
    size = len(buffer)
    stop = min(stop, start + WINDOW_BYTES, size)
    data = np.frombuffer(buffer, dtype=np.uint8)
    # Marker starts in [start, stop): compare the four marker bytes at every offset of the window.
    head = data[start:min(stop + MARKER_BYTES - 1, size)]
    found = np.ones(max(len(head) - MARKER_BYTES + 1, 0), dtype=bool)
    for i, byte in enumerate(MARKER):
        found &= head[i:len(head) - MARKER_BYTES + 1 + i] == byte
    starts = start + np.flatnonzero(found).astype(np.int64)
    starts = starts[starts + HEADER_BYTES + CRC.size <= size]
    lengths = _gather_uint32(data, starts + LENGTH_AT).astype(np.int64)
    ends = starts + HEADER_BYTES + lengths  # where each candidate's CRC is stored
    keep = (lengths <= MAX_PAYLOAD_BYTES) & (ends + CRC.size <= size)
    starts, ends = starts[keep], ends[keep]
    if not len(starts):
        return starts, stop
    covered = starts + MARKER_BYTES  # each CRC covers [covered, end)
    # The running CRC from the first covered byte, at every place a candidate's coverage starts or ends.
    places = np.unique(np.concatenate((covered, ends)))
    running = np.empty(len(places), dtype=np.uint32)
    view, crc, previous = memoryview(buffer), 0, int(places[0])
    for first in range(0, len(places), PLACES_AT_ONCE):  # as Python ints, a block at a time
        for i, place in enumerate(places[first:first + PLACES_AT_ONCE].tolist(), first):
            crc = zlib.crc32(view[previous:place], crc)
            running[i], previous = crc, place
    before = running[np.searchsorted(places, covered)]
    after = running[np.searchsorted(places, ends)]
    own = after ^ _shift(before, ends - covered)
    return starts[own == _gather_uint32(data, ends)], stop

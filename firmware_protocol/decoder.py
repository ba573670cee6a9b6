"""Incremental stream decoder: bytes in any chunking -> frames, with link-health counters.

It never raises on input bytes. It resynchronises on the sync byte; a candidate whose length is
impossible for its type, or whose CRC fails, gives up only its sync byte, so a corrupted or
truncated frame never swallows the intact frame that follows it. Every byte fed ends up in an
CRC-valid frame (``frame_bytes``), in ``bytes_skipped``, or still pending (less than one frame):
``bytes_in == frame_bytes + bytes_skipped + pending_bytes``.
"""

from __future__ import annotations

from binascii import crc_hqx
from dataclasses import dataclass, fields

from firmware_protocol.codec import CRC_BYTES, CRC_INIT, HEADER_BYTES, SYNC, Frame
from firmware_protocol.spec import SPEC, Spec

_OVERHEAD = HEADER_BYTES + CRC_BYTES
_CONFIG_ID = SPEC.frame("CONFIG").id
_FINGERPRINT_INDEX = SPEC.frame("CONFIG").field_names.index("schema_fingerprint")
_new = tuple.__new__  # Frame construction without a Python-level call (see codec.Frame)


def _lookup(spec: Spec) -> tuple[list, list, list, list]:
    """Per type id (0..255): the frame type, its payload size, unpacker and whether it is timestamped
    (None/False for ids the spec lacks): lists indexed in the hot loop."""
    by_id = {t.id: t for t in spec.frames}
    types = [by_id.get(i) for i in range(256)]
    return (types, [t.payload_size if t else None for t in types], [t.struct.unpack_from if t else None for t in types],
            [bool(t and t.has_timestamp) for t in types])


@dataclass
class DecoderStats:
    """Counters since the decoder was made. All are exact counts, none are rates."""

    bytes_in: int = 0
    frames: int = 0  # known-type frames returned
    crc_errors: int = 0  # candidates with a plausible header whose CRC failed
    bytes_skipped: int = 0  # bytes not part of any CRC-valid frame
    frame_bytes: int = 0  # bytes of CRC-valid frames (duplicates and unknown types included)
    frames_lost: int = 0  # gaps in the sender's sequence counter
    duplicates: int = 0  # a frame repeated byte for byte (same type, seq and values); dropped
    unknown_types: int = 0  # CRC-valid frames of a type this spec lacks; skipped
    bad_lengths: int = 0  # sync + type whose length byte is impossible for that type
    schema_mismatches: int = 0  # CONFIG frames from firmware built from another spec

    def as_dict(self) -> dict[str, int]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


class StreamDecoder:
    """Feed chunks of any size and boundary; get back the complete, valid, new frames."""

    def __init__(self, spec: Spec = SPEC) -> None:
        """``spec``: the protocol to decode (the project's own by default; tests decode others)."""
        self.spec = spec
        self._types, self._sizes, self._unpackers, self._timestamped = _lookup(spec)
        self.stats = DecoderStats()
        self.remote_fingerprint: int | None = None  # from the last CONFIG seen
        self._pending = b""
        self._last_seq: int | None = None
        self._last_raw: tuple | bytes = ()
        self._last_t32: int | None = None
        self._last_t64 = 0

    @property
    def pending_bytes(self) -> int:
        return len(self._pending)

    def feed(self, data: bytes | bytearray | memoryview) -> list[Frame]:
        data = self._pending + bytes(data)
        n = len(data)
        stats = self.stats
        stats.bytes_in += n - len(self._pending)
        out: list[Frame] = []
        append = out.append
        find = data.find
        # Locals, not globals, in the loop that runs a million times a second.
        sync, header, overhead, max_payload, crc_init = SYNC, HEADER_BYTES, _OVERHEAD, self.spec.max_payload_bytes, CRC_INIT
        sizes, unpackers, types, timestamped = self._sizes, self._unpackers, self._types, self._timestamped
        crc, new, frame_class = crc_hqx, _new, Frame
        skipped = crc_errors = bad_lengths = lost = duplicates = unknown = accepted = 0
        last_seq, last_raw = self._last_seq, self._last_raw
        last_t32, last_t64 = self._last_t32, self._last_t64
        pos = 0
        while True:
            start = find(sync, pos)
            if start < 0:
                skipped += n - pos
                pos = n
                break
            skipped += start - pos
            if start + header > n:
                pos = start
                break
            length = data[start + 1]
            type_id = data[start + 2]
            size = sizes[type_id]
            if length != size and (size is not None or length > max_payload):
                bad_lengths += 1
                skipped += 1
                pos = start + 1
                continue
            end = start + overhead + length
            if end > n:
                pos = start
                break
            # The CRC is sent big-endian, so a CRC over the frame including it is 0 when intact.
            if crc(data[start + 1 : end], crc_init):
                crc_errors += 1
                skipped += 1
                pos = start + 1
                continue
            accepted += end - start
            pos = end
            seq = data[start + 3]
            # Encoding is a function of (type, seq, values): equal values mean equal bytes.
            raw = unpackers[type_id](data, start + header) if size is not None else data[start:end]
            if seq == last_seq and raw == last_raw:
                duplicates += 1
                continue
            if last_seq is not None:
                lost += (seq - last_seq - 1) & 0xFF
            last_seq, last_raw = seq, raw
            if size is None:
                unknown += 1
                continue
            t64 = None
            if timestamped[type_id]:
                t32 = raw[0]
                if last_t32 is None:
                    t64 = t32
                else:  # the signed 32-bit difference unwraps the 71.6-minute wrap
                    step = (t32 - last_t32) & 0xFFFFFFFF
                    t64 = last_t64 + (step if step < 0x80000000 else step - 0x100000000)
                last_t32, last_t64 = t32, t64
            elif type_id == _CONFIG_ID:
                self._check_fingerprint(raw[_FINGERPRINT_INDEX])
            append(new(frame_class, (types[type_id], seq, raw, t64)))
        self._pending = data[pos:]
        self._last_seq, self._last_raw = last_seq, last_raw
        self._last_t32, self._last_t64 = last_t32, last_t64
        stats.frames += len(out)
        stats.bytes_skipped += skipped
        stats.frame_bytes += accepted
        stats.crc_errors += crc_errors
        stats.bad_lengths += bad_lengths
        stats.frames_lost += lost
        stats.duplicates += duplicates
        stats.unknown_types += unknown
        return out

    def _check_fingerprint(self, fingerprint: int) -> None:
        self.remote_fingerprint = fingerprint
        if fingerprint != SPEC.fingerprint:
            self.stats.schema_mismatches += 1

    @property
    def schema_matches(self) -> bool | None:
        """True/False once a CONFIG frame has been seen, None before."""
        if self.remote_fingerprint is None:
            return None
        return self.remote_fingerprint == SPEC.fingerprint

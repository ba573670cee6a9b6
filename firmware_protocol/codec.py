"""Frames as values, and their encoding into bytes on the wire.

Layout (see ``spec.toml``): ``sync | length | type | seq | payload | crc16``; fields little-endian,
the CRC-16/CCITT-FALSE over everything after the sync byte, sent big-endian (so that the CRC of an
intact frame including its CRC is zero).
"""

from __future__ import annotations

import math
from binascii import crc_hqx
from operator import itemgetter

from firmware_protocol.spec import SPEC, FrameType

CRC_INIT = 0xFFFF
SYNC = SPEC.sync
HEADER_BYTES = SPEC.header_bytes
CRC_BYTES = SPEC.crc_bytes
FRAME_TYPES_BY_ID: dict[int, FrameType] = {t.id: t for t in SPEC.frames}
FRAME_TYPES_BY_NAME: dict[str, FrameType] = {t.name: t for t in SPEC.frames}
_INDEX = {t.id: {name: i for i, name in enumerate(t.field_names)} for t in SPEC.frames}


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor)."""
    return crc_hqx(data, CRC_INIT)


class Frame(tuple):
    """One decoded or to-be-encoded frame: ``(type, seq, raw, device_time_us)``.

    ``raw`` holds the values exactly as on the wire (integers, or float for ``float`` fields), in
    the spec's field order. ``frame["acc_x"]`` reads one raw value; ``scaled()`` gives physical
    values (raw * scale, in the spec's unit). ``device_time_us`` is the decoder's 64-bit unwrapped
    device time for frames that carry ``t_us`` (None otherwise, and for frames not decoded).

    A tuple subclass because the decoder makes a million of these a second: building one is a
    single C call (``new_frame``), with no Python ``__init__``.
    """

    __slots__ = ()

    type: FrameType = property(itemgetter(0))  # type: ignore[assignment]
    seq: int = property(itemgetter(1))  # type: ignore[assignment]
    raw: tuple = property(itemgetter(2))  # type: ignore[assignment]
    device_time_us: int | None = property(itemgetter(3))  # type: ignore[assignment]

    @property
    def name(self) -> str:
        return self[0].name

    def __getitem__(self, key):
        if isinstance(key, str):
            return self[2][_INDEX[self[0].id][key]]
        return tuple.__getitem__(self, key)

    @property
    def values(self) -> dict[str, int | float]:
        return dict(zip(self.type.field_names, self.raw))

    def scaled(self) -> dict[str, float]:
        return {f.name: v * f.scale for f, v in zip(self.type.fields, self.raw)}

    def same_content(self, other: Frame) -> bool:
        """Same type, seq and values; the decoder's device time is not part of the wire content."""
        return (self.type.id, self.seq, self.raw) == (other.type.id, other.seq, other.raw)

    def __repr__(self) -> str:
        fields = ", ".join(f"{k}={v!r}" for k, v in self.values.items())
        return f"Frame({self.name}, seq={self.seq}, {fields})"


def new_frame(frame_type: FrameType, seq: int, raw: tuple, device_time_us: int | None = None) -> Frame:
    return tuple.__new__(Frame, (frame_type, seq, raw, device_time_us))


def make_frame(name: str, seq: int = 0, **values: int | float) -> Frame:
    """Build a frame from raw field values by name; every field of the type must be given."""
    frame_type = FRAME_TYPES_BY_NAME.get(name)
    if frame_type is None:
        raise ValueError(f"unknown frame type {name!r}; known: {', '.join(FRAME_TYPES_BY_NAME)}")
    missing = set(frame_type.field_names) - values.keys()
    extra = values.keys() - set(frame_type.field_names)
    if missing or extra:
        raise ValueError(f"{name}: missing fields {sorted(missing)}, unknown fields {sorted(extra)}")
    return new_frame(frame_type, seq, tuple(values[n] for n in frame_type.field_names))


def make_scaled_frame(name: str, seq: int = 0, **physical: float) -> Frame:
    """Build a frame from physical values (raw = round(value / scale)), saturating at the type's range."""
    frame_type = FRAME_TYPES_BY_NAME[name]
    raw = {}
    for field in frame_type.fields:
        value = physical[field.name] / field.scale
        if field.c_type != "float":
            low, high = field.raw_range
            value = int(min(max(math.floor(value + 0.5), low), high))
        raw[field.name] = value
    return make_frame(name, seq, **raw)


def encode(frame: Frame) -> bytes:
    """The frame's bytes on the wire. Raises ValueError for values outside their C type."""
    frame_type = frame.type
    if not 0 <= frame.seq <= 255:
        raise ValueError(f"{frame_type.name}: seq {frame.seq} does not fit one byte")
    try:
        payload = frame_type.struct.pack(*frame.raw)
    except Exception as error:  # struct.error or OverflowError, both say which value is bad
        raise ValueError(f"{frame_type.name}: {error}") from None
    body = bytes((len(payload), frame_type.id, frame.seq)) + payload
    return bytes((SYNC,)) + body + crc16(body).to_bytes(2, "big")

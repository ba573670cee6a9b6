"""The telemetry wire protocol shared by the flight firmware, the radio bridge and the ground station.

``spec.toml`` is the single source of truth; this package reads it and provides the codec::

    frame = make_frame("IMU_RAW", seq=7, t_us=1000, acc_x=0, ...)
    data = encode(frame)
    decoder = StreamDecoder()
    frames = decoder.feed(data)     # any chunking; counters in decoder.stats
"""

from firmware_protocol.codec import Frame, crc16, encode, make_frame, make_scaled_frame
from firmware_protocol.decoder import DecoderStats, SequenceRules, StreamDecoder
from firmware_protocol.spec import SPEC, Field, FrameType, Spec, load_spec

__all__ = [
    "SPEC",
    "DecoderStats",
    "Field",
    "Frame",
    "FrameType",
    "SequenceRules",
    "Spec",
    "StreamDecoder",
    "crc16",
    "encode",
    "load_spec",
    "make_frame",
    "make_scaled_frame",
]

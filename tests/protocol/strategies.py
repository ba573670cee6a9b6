"""Hypothesis strategies for frames of every type with values over their full C ranges."""

from hypothesis import strategies as st

from firmware_protocol import SPEC, make_frame
from firmware_protocol.spec import Field, FrameType


def field_values(field: Field) -> st.SearchStrategy:
    if field.c_type == "float":
        return st.floats(width=32, allow_nan=False)
    low, high = field.raw_range
    return st.integers(int(low), int(high))


def frames_of(frame_type: FrameType, seq: st.SearchStrategy = st.integers(0, 255)) -> st.SearchStrategy:
    values = st.fixed_dictionaries({f.name: field_values(f) for f in frame_type.fields})
    return st.builds(lambda s, v: make_frame(frame_type.name, s, **v), seq, values)


any_frame = st.sampled_from(SPEC.frames).flatmap(frames_of)

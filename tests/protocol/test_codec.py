"""Encoding: the byte layout, the CRC, round trips of every frame type, the golden vectors."""

import json
import struct
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import firmware_protocol
from firmware_protocol import SPEC, StreamDecoder, crc16, encode, make_frame, make_scaled_frame

from .strategies import any_frame, frames_of

GOLDEN_DIR = Path(firmware_protocol.__file__).parent / "golden"


def bitwise_crc16_ccitt_false(data: bytes) -> int:
    """An independent CRC-16/CCITT-FALSE, bit by bit, straight from its definition."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def test_crc_is_ccitt_false_by_its_check_value():
    assert crc16(b"123456789") == 0x29B1  # the catalogued check value of CRC-16/CCITT-FALSE
    assert bitwise_crc16_ccitt_false(b"123456789") == 0x29B1


def test_imu_raw_bytes_match_the_documented_layout_built_by_hand():
    values = dict(t_us=0x01020304, acc_x=-2, acc_y=300, acc_z=16384, gyr_x=-32768, gyr_y=32767, gyr_z=0, temperature=2512)
    data = encode(make_frame("IMU_RAW", 0x7E, **values))
    payload = struct.pack("<I7h", 0x01020304, -2, 300, 16384, -32768, 32767, 0, 2512)
    body = bytes([len(payload), 0x01, 0x7E]) + payload
    assert data == b"\xa5" + body + bitwise_crc16_ccitt_false(body).to_bytes(2, "big")


def test_every_frame_fits_one_radio_payload():
    for frame_type in SPEC.frames:
        frame = make_frame(frame_type.name, 0, **{f.name: 0 for f in frame_type.fields})
        assert len(encode(frame)) <= 32


@settings(max_examples=300)
@given(any_frame)
def test_round_trip_of_any_frame(frame):
    data = encode(frame)
    assert len(data) == frame.type.payload_size + 6
    decoded = StreamDecoder().feed(data)
    assert len(decoded) == 1
    assert decoded[0].same_content(frame)


FLOAT32_MAX = struct.unpack("<f", struct.pack("<I", 0x7F7FFFFF))[0]


@pytest.mark.parametrize("frame_type", SPEC.frames, ids=lambda t: t.name)
@settings(max_examples=40)
@given(data=st.data())
def test_round_trip_per_type(frame_type, data):
    """Each type explicitly (the mixed test above could favour some), values over the full range."""
    frame = data.draw(frames_of(frame_type))
    (decoded,) = StreamDecoder().feed(encode(frame))
    assert decoded.values == frame.values


@pytest.mark.parametrize("frame_type", SPEC.frames, ids=lambda t: t.name)
@pytest.mark.parametrize("end", [0, 1], ids=["lowest", "highest"])
def test_round_trip_at_the_range_limits(frame_type, end):
    def limit(field):
        if field.c_type == "float":
            return (-FLOAT32_MAX, FLOAT32_MAX)[end]
        return int(field.raw_range[end])

    values = {f.name: limit(f) for f in frame_type.fields}
    (decoded,) = StreamDecoder().feed(encode(make_frame(frame_type.name, 255 * end, **values)))
    assert decoded.values == values and decoded.seq == 255 * end


def test_values_outside_their_c_type_are_refused():
    frame = make_frame("ACK", 0, command_seq=256, command=1, result=0)
    with pytest.raises(ValueError, match="ACK"):
        encode(frame)
    with pytest.raises(ValueError, match="seq"):
        encode(make_frame("ACK", 300, command_seq=1, command=1, result=0))


def test_make_frame_names_missing_and_unknown_fields():
    with pytest.raises(ValueError, match="missing fields.*unknown fields"):
        make_frame("ACK", 0, command_seq=1, bogus=2)
    with pytest.raises(ValueError, match="unknown frame type"):
        make_frame("NOPE")


def test_scaled_frame_rounds_and_saturates():
    frame = make_scaled_frame("BARO", 0, t_us=5, pressure=101325.004, temperature=400.0)
    assert frame["pressure"] == 10132500
    assert frame["temperature"] == 32767  # 400 degC does not fit int16 at 0.01: saturated


@pytest.mark.parametrize("frame_type", SPEC.frames, ids=lambda t: t.name)
def test_golden_vector(frame_type):
    name = frame_type.name.lower()
    data = (GOLDEN_DIR / f"{name}.bin").read_bytes()
    expected = json.loads((GOLDEN_DIR / f"{name}.json").read_text())
    assert encode(make_frame(expected["name"], expected["seq"], **expected["values"])) == data
    (decoded,) = StreamDecoder().feed(data)
    assert decoded.name == expected["name"] and decoded.seq == expected["seq"]
    assert decoded.values == expected["values"]
    assert decoded.scaled() == pytest.approx(expected["scaled"], rel=1e-12)

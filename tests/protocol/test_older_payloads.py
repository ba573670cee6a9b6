"""A frame type grows only at its end: a payload from an older sender is read, its missing fields absent.

The fixture is a genuine recording made before CONFIG gained ``gyro_calibration`` (its 15-byte CONFIG
says ±4 g, ±500 °/s): the first 400 chunks of ``recordings/samples/hover-raw.gsrec`` at commit 36f9bf7,
its records copied byte for byte (tests/data/README.md).
"""

import struct
from pathlib import Path

import numpy as np
import pytest

from firmware_protocol import SPEC, StreamDecoder, crc16
from firmware_protocol.batch import decode_batch
from firmware_protocol.spec import SPEC_PATH, SpecError, load_spec
from groundstation.recording import open_recording

from .test_batch import assert_same, incremental

OLD_RECORDING = Path(__file__).resolve().parents[1] / "data" / "hover-raw-config-15-bytes.gsrec"
CALIBRATION = SPEC.frame("CONFIG").field("gyro_calibration")
UNKNOWN = CALIBRATION.absent


def test_an_old_recordings_15_byte_config_is_read_by_both_decoders_with_the_new_field_unknown():
    chunks = list(open_recording(OLD_RECORDING).chunks())
    frames, decoder, _ = incremental(chunks)
    assert_same(chunks)  # the batch decode gives the same frames, counters and tail
    assert decoder.stats.bad_lengths == 0 and decoder.stats.bytes_skipped == 0
    configs = [raw for name, _, raw, _, _ in frames if name == "CONFIG"]
    assert len(configs) == 1
    config = dict(zip(SPEC.frame("CONFIG").field_names, configs[0]))
    assert (config["accel_fs_g"], config["gyro_fs_dps"], config["rate_hz"], config["mounting"]) == (4, 500, 100, 1)
    assert config["gyro_calibration"] == UNKNOWN
    assert SPEC.enum_name(CALIBRATION, config["gyro_calibration"]) == "unknown"
    assert decoder.schema_matches is True  # built from the older spec, whose CONFIG ours grew at its end: compatible


# A spec whose STATUS (timestamped) and CONFIG grew by two fields each: one numeric, one enum.
GROWN = SPEC_PATH.read_text(encoding="utf-8").replace(
    'description = "bit 0 gyro calibration running, bit 1 low battery, bit 2 IMU error, bit 3 radio TX FIFO overflow" },',
    'description = "bit 0 gyro calibration running, bit 1 low battery, bit 2 IMU error, bit 3 radio TX FIFO overflow" },\n'
    '  { name = "current", type = "int16_t", unit = "mA", absent = -32768, description = "later" },\n'
    '  { name = "fix", type = "uint8_t", unit = "enum", enum = "gps_fix", absent = 255, description = "later still" },',
)


def frame_bytes(type_id: int, seq: int, payload: bytes) -> bytes:
    body = bytes((len(payload), type_id, seq)) + payload
    return bytes((SPEC.sync,)) + body + crc16(body).to_bytes(2, "big")


def test_every_older_layout_of_a_grown_frame_is_read_and_a_cut_field_is_not():
    spec = load_spec(GROWN)
    status = spec.frame("STATUS")
    assert sorted(status.readers) == [13, 15, 16]
    base = struct.pack("<IHHHBH", 0, 12_000, 1, 2, 40, 0)
    payloads = [base, base + struct.pack("<h", -500), base + struct.pack("<hB", -500, 3), base + b"\x01"]  # the last: a cut field
    stream = b"".join(frame_bytes(status.id, seq, struct.pack("<I", 10_000 * seq) + p[4:]) for seq, p in enumerate(payloads))
    decoder = StreamDecoder(spec)
    frames = decoder.feed(stream)
    assert [f.raw[-2:] for f in frames] == [(-32768, 255), (-500, 255), (-500, 3)]
    assert decoder.stats.bad_lengths == 1
    batch = decode_batch(stream, spec=spec).frames["STATUS"]
    assert [tuple(r)[-2:] for r in batch.raw.tolist()] == [(-32768, 255), (-500, 255), (-500, 3)]
    assert batch.device_time_us.tolist() == [f.device_time_us for f in frames]


@pytest.mark.parametrize("fields, message", [
    ('{ name = "a", type = "uint8_t", unit = "1", absent = 0, description = "" },\n'
     '  { name = "b", type = "uint8_t", unit = "1", description = "" },', "must come after"),
    ('{ name = "a", type = "uint8_t", unit = "1", description = "" },\n'
     '  { name = "b", type = "uint8_t", unit = "enum", enum = "mode", absent = 0, description = "" },', "is a member"),
    ('{ name = "a", type = "uint8_t", unit = "1", description = "" },\n'
     '  { name = "b", type = "uint8_t", unit = "1", absent = 256, description = "" },', "is not a uint8_t"),
])
def test_the_spec_refuses_an_appended_field_before_a_sent_one_or_an_absent_value_that_is_no_absence(fields, message):
    text = SPEC_PATH.read_text(encoding="utf-8") + (
        f'\n[[frames]]\nname = "LATER"\nid = 0x20\ndirection = "down"\ndescription = ""\nfields = [\n  {fields}\n]\n')
    with pytest.raises(SpecError, match=message):
        load_spec(text)


def test_the_batch_columns_of_an_old_config_hold_the_absent_value():
    chunks = list(open_recording(OLD_RECORDING).chunks())
    columns = decode_batch(b"".join(d for _, d in chunks)).frames["CONFIG"]
    assert columns.raw["gyro_calibration"].tolist() == [UNKNOWN]
    assert np.array_equal(columns.raw["accel_fs_g"], [4])

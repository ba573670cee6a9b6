"""The columnar batch decode against the incremental StreamDecoder fed the same bytes chunk by chunk.

The incremental decoder is the oracle: every frame (type, seq, raw values, unwrapped device time,
arrival time of the chunk that completed it), every counter and the pending tail must be identical,
on clean streams, on streams damaged in every way the link damages them, and on long streams whose
device time and sequence counter wrap.
"""

import math
import random
import struct

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from firmware_protocol import SPEC, StreamDecoder, crc16, encode, make_frame
from firmware_protocol.batch import CHUNK_COUNTERS, decode_batch, decode_chunks, payload_dtype
from firmware_protocol.codec import new_frame

from tests.simulated import simulated_chunks

from .strategies import any_frame

SYNC = SPEC.sync
batch_settings = settings(max_examples=200, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
FATES = ["intact", "intact", "flip", "truncate", "duplicate", "drop", "garbage", "unknown_type", "bad_length"]


def chunked(data: bytes, rng: random.Random, max_chunk: int) -> list[tuple[int, bytes]]:
    chunks, pos, t_ns = [], 0, rng.randrange(10**12)
    while pos < len(data):
        size = rng.randint(1, max_chunk)
        t_ns += rng.randint(1, 10**7)
        chunks.append((t_ns, data[pos : pos + size]))
        pos += size
    return chunks


def key(raw) -> tuple:
    """Raw values comparable with NaN (a float field may carry one)."""
    return tuple("nan" if isinstance(v, float) and math.isnan(v) else v for v in raw)


def incremental(chunks):
    """The frames as rows, the decoder, and its link counters after each chunk."""
    decoder = StreamDecoder()
    out, counters = [], []
    for t_ns, data in chunks:
        out += [(f.name, f.seq, key(f.raw), f.device_time_us, t_ns) for f in decoder.feed(data, t_ns)]
        counters.append([getattr(decoder.stats, c) for c in CHUNK_COUNTERS])
    return out, decoder, counters


def batch_rows(result):
    """The batch result as the same rows, merged back into stream order."""
    rows = []
    for name, columns in result.frames.items():
        assert columns.raw.dtype == payload_dtype(SPEC.frame(name))
        for k in range(len(columns)):
            t64 = None if columns.device_time_us is None else int(columns.device_time_us[k])
            raw = key(columns.raw[k].item())
            rows.append((int(columns.order[k]), (name, int(columns.seq[k]), raw, t64, int(columns.t_host_ns[k]))))
    rows.sort()
    assert [order for order, _ in rows] == list(range(len(rows)))  # order is a permutation of 0..N-1
    return [row for _, row in rows]


def assert_same(chunks):
    expected, decoder, counters = incremental(chunks)
    result = decode_chunks(chunks)
    assert batch_rows(result) == expected
    assert result.stats == decoder.stats
    assert result.pending_bytes == decoder.pending_bytes
    assert result.remote_fingerprint == decoder.remote_fingerprint
    assert result.rate_hz == decoder.rate_hz
    batch_counters = np.column_stack([result.chunk_counters[c] for c in CHUNK_COUNTERS]) if chunks else np.zeros((0, 5))
    assert batch_counters.tolist() == counters
    return result


def numbered(frames, first_seq=0):
    return [new_frame(f.type, (first_seq + i) & 0xFF, f.raw) for i, f in enumerate(frames)]


def unknown_frame(seq: int, payload: bytes) -> bytes:
    type_id = next(i for i in range(256) if i not in {t.id for t in SPEC.frames})
    body = bytes([len(payload), type_id, seq]) + payload
    return bytes([SYNC]) + body + crc16(body).to_bytes(2, "big")


def damaged_stream(frames, fates, noises, rng: random.Random) -> bytes:
    stream = bytearray()
    for frame, fate, noise in zip(frames, fates, noises):
        data = encode(frame)
        if fate == "flip":  # one bit anywhere, sync and header included
            i = rng.randrange(len(data))
            data = data[:i] + bytes([data[i] ^ (1 << rng.randrange(8))]) + data[i + 1 :]
        elif fate == "truncate":
            data = data[: rng.randrange(1, len(data))]
        elif fate == "duplicate":
            data = data + data
        elif fate == "drop":
            data = b""
        elif fate == "garbage":  # any bytes, sync bytes and fragments of frames included
            data = noise + data
        elif fate == "unknown_type":
            data = unknown_frame(frame.seq, noise[: SPEC.max_payload_bytes]) + data
        elif fate == "bad_length":
            data = bytes([SYNC, SPEC.max_payload_bytes + 1, frame.type.id]) + data
        stream += data
    return bytes(stream)


@batch_settings
@given(st.lists(any_frame, min_size=0, max_size=80), st.randoms(use_true_random=False), st.integers(1, 4096))
def test_clean_stream_in_any_chunking(frames, rng, max_chunk):
    assert_same(chunked(b"".join(encode(f) for f in numbered(frames)), rng, max_chunk))


@batch_settings
@given(
    st.lists(any_frame, min_size=1, max_size=80),
    st.lists(st.sampled_from(FATES), min_size=80, max_size=80),
    st.lists(st.binary(min_size=1, max_size=40), min_size=80, max_size=80),
    st.randoms(use_true_random=False),
    st.integers(1, 64),
    st.binary(max_size=40),
)
def test_damaged_stream_gives_the_same_frames_and_counters(frames, fates, noises, rng, max_chunk, tail):
    """Bit flips, truncations, garbage with sync bytes, duplicates, drops, unknown types, impossible
    lengths; the stream may start and end anywhere (the tail may leave a frame pending)."""
    stream = damaged_stream(numbered(frames, rng.randrange(256)), fates, noises, rng)
    assert_same(chunked(stream[rng.randrange(3) :] + tail, rng, max_chunk))


@settings(max_examples=300, derandomize=True)
@given(st.binary(max_size=3000), st.randoms(use_true_random=False))
def test_any_bytes(data, rng):
    assert_same(chunked(data, rng, 300))


def test_repeated_duplicates_and_equal_seq_with_other_values():
    imu = SPEC.frame("IMU_RAW")
    a = make_frame("IMU_RAW", 5, **dict.fromkeys(imu.field_names, 1))
    b = make_frame("IMU_RAW", 5, **dict.fromkeys(imu.field_names, 2))  # same seq, other values: kept
    stream = encode(a) * 4 + encode(b) + encode(a) + encode(b) * 2
    result = assert_same([(1, stream)])
    assert (result.stats.duplicates, result.stats.frames) == (4, 4)


def test_float_nan_repeat_is_not_a_duplicate():
    """NaN != NaN, so StreamDecoder keeps a repeated frame with a NaN value; the batch does too."""
    command = SPEC.frame("COMMAND")
    values = {f.name: (math.nan if f.c_type == "float" else 1) for f in command.fields}
    stream = encode(make_frame("COMMAND", 3, **values)) * 2
    result = assert_same([(1, stream)])
    assert result.stats.duplicates == 0 and len(result.frames["COMMAND"]) == 2


def test_crc_valid_frame_hidden_inside_another_is_resolved_like_the_scan():
    """A whole frame inside a longer frame's payload: the scan accepts the outer one only; the inner
    one is accepted where the outer frame is broken."""
    inner = encode(make_frame("ACK", 9, command_seq=1, command=1, result=0))
    status = SPEC.frame("STATUS")
    payload = inner + bytes(status.payload_size - len(inner))
    outer_body = bytes([status.payload_size, status.id, 8]) + payload
    outer = bytes([SYNC]) + outer_body + crc16(outer_body).to_bytes(2, "big")
    broken = outer[:-1] + bytes([outer[-1] ^ 1])
    result = assert_same([(1, outer + broken + outer)])
    assert len(result.frames["STATUS"]) == 2 and len(result.frames["ACK"]) == 1


def test_a_frame_behind_a_truncated_longer_header_comes_out_with_the_later_chunk():
    """The incremental decoder waits for the bytes a damaged header announces before it decides on
    it, so the intact frame after it is returned with the chunk that brings those bytes."""
    status = encode(make_frame("STATUS", 1, t_us=5, battery=1, retransmits=2, lost_acks=3, cpu_load=4, flags=5))
    ack = encode(make_frame("ACK", 2, command_seq=1, command=1, result=0))
    assert len(ack) < len(status) - 6
    result = assert_same([(100, status[:6] + ack), (200, bytes(SPEC.max_frame_bytes))])
    assert result.frames["ACK"].t_host_ns.tolist() == [200]


def imu(seq: int, t_us: int):
    return make_frame("IMU_RAW", seq & 0xFF, t_us=t_us & 0xFFFFFFFF, acc_x=seq % 7, acc_y=2, acc_z=3, gyr_x=4, gyr_y=5, gyr_z=6, temperature=7)


def test_long_stream_wraps_device_time_and_sequence_with_damage():
    """20,000 frames over two 32-bit device-time wraps and a device reset, with damage throughout."""
    rng = random.Random(15)
    step_us = 2**19  # 2**32 / 2**19 = 8192 frames per wrap
    frames, t = [], 2**32 - 3_000 * step_us
    for i in range(20_000):
        t = 0 if i == 12_345 else t + step_us  # a reboot: time jumps back to 0
        frames.append(imu(i, t))
    fates = [rng.choice(FATES) if rng.random() < 0.05 else "intact" for _ in frames]
    noises = [bytes(rng.randrange(256) for _ in range(rng.randint(1, 30))) for _ in frames]
    stream = damaged_stream(frames, fates, noises, rng)
    result = assert_same(chunked(stream, rng, 4096))
    times = result.frames["IMU_RAW"].device_time_us
    assert times.max() > 2**33  # two wraps unwrapped into 64 bits
    assert result.stats.crc_errors > 0 and result.stats.duplicates > 0 and result.stats.frames_lost > 0


def test_raw_values_are_the_wire_values_bit_for_bit():
    frame_type = SPEC.frame("GPS")
    rng = random.Random(3)
    frames = []
    for i in range(50):
        values = {}
        for f in frame_type.fields:
            low, high = f.raw_range
            values[f.name] = struct.unpack("<f", rng.randbytes(4))[0] if f.c_type == "float" else rng.randint(int(low), int(high))
        values["t_us"] = 1000 * i  # a steady clock: a random one would be dropped as implausible
        frames.append(make_frame("GPS", i, **values))
    result = decode_batch(b"".join(encode(f) for f in frames))
    assert result.frames["GPS"].raw.tobytes() == b"".join(encode(f)[4:-2] for f in frames)
    assert np.array_equal(result.frames["GPS"].seq, np.arange(50))
    for field in frame_type.fields:  # physical values: the same numbers as Frame.scaled
        expected = [f.scaled()[field.name] for f in frames]
        np.testing.assert_array_equal(result.frames["GPS"].scaled(field.name), expected)


SENSORS = dict(mag_rate_hz=50, baro_rate_hz=25, gps_rate_hz=5)


def assert_mishaps_decoded(assert_decoded, duration_s: float) -> None:
    """The simulator's board mishaps and link damage over ``duration_s`` at 100 Hz with every sensor, each through
    ``assert_decoded(chunks)`` (which compares two decodes and returns one): a reboot, a clock jump, a bad link
    with a reboot, each seen in the decoder's counters."""
    reboot = assert_decoded(simulated_chunks(duration_s, reboot_after_s=3.0, usb_batch_ms=4.0, **SENSORS))
    assert reboot.stats.restarts == 1
    jump = assert_decoded(simulated_chunks(duration_s, clock_jump_after_s=duration_s / 2, latency_ms=3.0, jitter_ms=2.0, **SENSORS))
    assert jump.stats.restarts == 1
    bad = assert_decoded(simulated_chunks(duration_s, loss=0.05, burst_loss=0.05, ber=2e-4, truncate=0.01,
                                          reboot_after_s=duration_s - 3.0, **SENSORS))
    assert bad.stats.crc_errors > 0 and bad.stats.frames_lost > 0


def test_simulated_sessions_with_reboots_clock_jumps_and_a_bad_link():
    """The same frames, device times and counters (restarts, implausible frames and losses included)."""
    assert_mishaps_decoded(assert_same, 8.0)


def test_both_decoders_hand_the_same_frames_to_the_one_set_of_sequence_rules(monkeypatch):
    """``SequenceRules`` is the only place the sequence and time rules live: on a damaged stream with a
    reboot, the incremental and the batch decoder call it for the same frames with the same state."""
    from firmware_protocol.decoder import SequenceRules

    calls = []
    timed, untimed = SequenceRules.timed, SequenceRules.untimed

    def record(name, rule):
        def called(self, *args):
            frame = args[1:4] if name == "timed" else args[:3]
            calls.append((name, args[-1], self.next_seq, self.t32, self.t64, self.fast_us,
                          *(key(a) if isinstance(a, tuple) else a for a in frame)))
            return rule(self, *args)
        return called

    monkeypatch.setattr(SequenceRules, "timed", record("timed", timed))
    monkeypatch.setattr(SequenceRules, "untimed", record("untimed", untimed))
    chunks = simulated_chunks(6.0, loss=0.05, burst_loss=0.05, ber=3e-4, reboot_after_s=3.0)
    incremental(chunks)
    by_stream, calls[:] = list(calls), []
    decode_chunks(chunks)
    assert len(by_stream) > 50 and calls == by_stream


def test_the_batch_decoder_reads_no_private_state_of_another_object():
    """The rules are driven through their public interface, never through another object's ``_`` attributes."""
    import ast
    import inspect

    import firmware_protocol.batch

    tree = ast.parse(inspect.getsource(firmware_protocol.batch))
    private = sorted({node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute) and node.attr.startswith("_")
                      and not node.attr.startswith("__") and not (isinstance(node.value, ast.Name) and node.value.id == "self")})
    assert private == []

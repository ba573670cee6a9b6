"""The stream decoder against streams whose damage the test knows exactly."""

import random

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from firmware_protocol import SPEC, StreamDecoder, crc16, encode, make_frame
from firmware_protocol.codec import new_frame

from .strategies import any_frame

SYNC = SPEC.sync
# Derandomised: a CRC-16 accepts one corrupted candidate in 65,536; a fixed set of examples keeps
# that from failing a rare run by chance, and keeps every failure reproducible.
stream_settings = settings(max_examples=150, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
IDLE = bytes(SPEC.max_frame_bytes)  # what a quiet link sends: no sync byte
FATES = ["intact", "corrupt", "truncate", "duplicate", "drop", "garbage"]


def feed_in_random_chunks(decoder: StreamDecoder, data: bytes, rng: random.Random, max_chunk: int = 40) -> list:
    frames, pos = [], 0
    while pos < len(data):
        size = rng.randint(1, max_chunk)
        frames += decoder.feed(data[pos : pos + size])
        pos += size
    return frames


def numbered(frames, period_us: int = 10_000):
    """Consecutive sequence numbers and rising timestamps, as the aircraft's sender gives them."""
    return [new_frame(f.type, i & 0xFF, (i * period_us,) + f.raw[1:] if f.type.has_timestamp else f.raw)
            for i, f in enumerate(frames)]


def frame_bytes(frames) -> int:
    return sum(len(encode(f)) for f in frames)


def check_byte_accounting(decoder: StreamDecoder) -> None:
    s = decoder.stats
    assert s.bytes_in == s.frame_bytes + s.bytes_skipped + decoder.pending_bytes
    assert decoder.pending_bytes < SPEC.max_frame_bytes


@stream_settings
@given(st.lists(any_frame, min_size=1, max_size=60), st.randoms(use_true_random=False))
def test_intact_stream_in_any_chunking_decodes_every_frame_once(frames, rng):
    frames = numbered(frames)
    decoder = StreamDecoder()
    decoded = feed_in_random_chunks(decoder, b"".join(encode(f) for f in frames), rng)
    assert [(f.seq, f.values) for f in decoded] == [(f.seq, f.values) for f in frames]
    s = decoder.stats
    assert (s.frames, s.crc_errors, s.bytes_skipped, s.frames_lost, s.duplicates, s.bad_lengths) == (len(frames), 0, 0, 0, 0, 0)
    assert decoder.pending_bytes == 0


@stream_settings
@given(
    st.lists(any_frame, min_size=2, max_size=50),
    st.lists(st.sampled_from(FATES), min_size=50, max_size=50),
    st.randoms(use_true_random=False),
)
def test_damaged_stream_counters_are_exact(frames, fates, rng):
    """Damage that cannot fake a sync byte, so that every counter is predictable exactly."""
    frames = numbered(frames)
    stream = bytearray()
    delivered, expected = [], dict(crc_errors=0, bytes_skipped=0, duplicates=0)
    accepted = 0
    for frame, fate in zip(frames, fates):
        data = encode(frame)
        if SYNC in data[1:]:
            fate = "drop"  # a sync inside the frame would make extra candidates after damage
        if fate == "corrupt":  # one bit flipped in the payload or CRC, never making a sync byte
            i, bit = rng.randrange(4, len(data)), 1 << rng.randrange(8)
            while data[i] ^ bit == SYNC:
                i, bit = rng.randrange(4, len(data)), 1 << rng.randrange(8)
            stream += data[:i] + bytes([data[i] ^ bit]) + data[i + 1 :]
            expected["crc_errors"] += 1
            expected["bytes_skipped"] += len(data)
            continue
        if fate == "truncate":  # header complete, the rest cut short; the next frame follows
            cut = rng.randrange(4, len(data))
            stream += data[:cut]
            expected["crc_errors"] += 1
            expected["bytes_skipped"] += cut
            continue
        if fate == "drop":
            continue
        if fate == "garbage":  # noise without a sync byte before an intact frame
            noise = bytes(rng.choice([b for b in range(256) if b != SYNC]) for _ in range(rng.randint(1, 30)))
            stream += noise
            expected["bytes_skipped"] += len(noise)
        if fate == "duplicate":
            stream += data
            accepted += len(data)
            expected["duplicates"] += 1
        stream += data
        accepted += len(data)
        delivered.append(frame)
    # The link goes on: a frame's worth of idle bytes lets a trailing candidate fail, then one last frame.
    closing = encode(make_frame("ACK", len(frames) & 0xFF, command_seq=0, command=1, result=0))
    stream += IDLE + closing
    expected["bytes_skipped"] += len(IDLE)
    accepted += len(closing)

    decoder = StreamDecoder()
    decoded = feed_in_random_chunks(decoder, bytes(stream), rng)
    assert [(f.seq, f.values) for f in decoded[:-1]] == [(f.seq, f.values) for f in delivered]
    s = decoder.stats
    assert {k: getattr(s, k) for k in expected} == expected
    # Every frame sent after the first decoded one and not decoded is counted lost.
    assert s.frames_lost == (len(frames) + 1 - decoded[0].seq) - len(decoded)
    assert (s.bad_lengths, s.unknown_types) == (0, 0)
    assert s.frame_bytes == accepted
    check_byte_accounting(decoder)


@stream_settings
@given(
    st.lists(any_frame, min_size=1, max_size=40),
    st.lists(st.tuples(st.sampled_from(["flip", "garbage", "truncate"]), st.binary(min_size=1, max_size=40)), max_size=40),
    st.randoms(use_true_random=False),
)
@example(frames=[new_frame(SPEC.frame("BARO"), 0, (0, 0, 0)), new_frame(SPEC.frame("BARO"), 0, (0, 67808, -14446)),
                 *[new_frame(SPEC.frame("IMU_RAW"), 0, (0,) * 8)] * 2], damages=[("truncate", b"\x00")] * 4,
         rng=random.Random(0))
def test_arbitrary_damage_never_loses_an_intact_frame_or_accepts_a_broken_one(frames, damages, rng):
    """Garbage of any bytes (sync bytes included), bit flips anywhere, truncations anywhere."""
    frames = numbered(frames)
    fates = [damages[i] if i < len(damages) else ("none", b"") for i in range(len(frames))]
    encoded = [encode(frame) for frame in frames]
    # what the wire carries after frame i: the next frame's garbage, else its first byte, else the idle link
    after = [(fates[i + 1][1] if fates[i + 1][0] == "garbage" else encoded[i + 1])[0] if i + 1 < len(frames) else IDLE[0]
             for i in range(len(frames))]
    stream, intact = bytearray(), []
    for i, (frame, data, (kind, noise)) in enumerate(zip(frames, encoded, fates)):
        if kind == "flip":
            j = rng.randrange(len(data))
            data = data[:j] + bytes([data[j] ^ (1 << rng.randrange(8))]) + data[j + 1 :]
        elif kind == "truncate":
            # Cut where the first byte lost differs from the byte that follows: a frame whose lost tail is what
            # comes next is whole on the wire (found: a CRC ending in the next frame's sync byte, cut by one).
            cuts = [j for j in range(1, len(data)) if data[j] != after[i]]
            data = data[: rng.choice(cuts)]
        else:
            if kind == "garbage":
                stream += noise
            intact.append(frame)
        stream += data
    decoder = StreamDecoder()
    decoded = feed_in_random_chunks(decoder, bytes(stream + IDLE), rng)
    # Every intact frame decodes exactly once; nothing else is accepted.
    assert [(f.seq, f.values) for f in decoded] == [(f.seq, f.values) for f in intact]
    assert decoder.stats.frame_bytes == frame_bytes(decoded)
    check_byte_accounting(decoder)


@settings(max_examples=300)
@given(st.binary(max_size=2000), st.randoms(use_true_random=False))
def test_any_bytes_never_raise_and_every_byte_is_accounted_for(data, rng):
    decoder = StreamDecoder()
    decoded = feed_in_random_chunks(decoder, data, rng)
    check_byte_accounting(decoder)
    assert decoder.stats.frames == len(decoded)


def imu(seq: int, t_us: int):
    return make_frame("IMU_RAW", seq & 0xFF, t_us=t_us & 0xFFFFFFFF, acc_x=1, acc_y=2, acc_z=3, gyr_x=4, gyr_y=5, gyr_z=6, temperature=7)


def test_device_time_unwraps_across_the_32_bit_wrap():
    start = 2**32 - 35_000  # 35 ms before the wrap, 10 ms steps
    frames = [imu(i, start + 10_000 * i) for i in range(10)]
    decoded = StreamDecoder().feed(b"".join(encode(f) for f in frames))
    times = [f.device_time_us for f in decoded]
    assert times == [start + 10_000 * i for i in range(10)]  # 64-bit, monotonic, exact
    assert decoded[5]["t_us"] < decoded[3]["t_us"]  # the raw field did wrap


def test_device_time_survives_many_wraps_in_one_session():
    decoder, t = StreamDecoder(), 0
    step_us = 2**31 - 1  # the largest step that is still unambiguous
    for i in range(10):
        (frame,) = decoder.feed(encode(imu(i, t)))
        assert frame.device_time_us == t
        t += step_us


def test_sequence_gap_across_the_counter_wrap_counts_lost_frames():
    decoder = StreamDecoder()
    decoder.feed(encode(imu(250, 0)) + encode(imu(251, 10)) + encode(imu(3, 20)))  # 252..255, 0..2 missing
    assert decoder.stats.frames_lost == 7


def test_unknown_frame_type_is_counted_and_skipped_cleanly():
    body = bytes([5, 0x7F, 0]) + b"\x01\x02\x03\x04\x05"
    unknown = bytes([SYNC]) + body + crc16(body).to_bytes(2, "big")
    decoder = StreamDecoder()
    decoded = decoder.feed(unknown + encode(imu(1, 10)))
    assert [f.name for f in decoded] == ["IMU_RAW"]
    assert (decoder.stats.unknown_types, decoder.stats.bytes_skipped, decoder.stats.frames_lost) == (1, 0, 0)


def test_impossible_length_gives_up_only_the_sync_byte():
    bad = bytes([SYNC, 3, 0x01, 0])  # IMU_RAW never has 3 payload bytes
    decoder = StreamDecoder()
    decoded = decoder.feed(bad + encode(imu(0, 0)))
    assert len(decoded) == 1
    assert (decoder.stats.bad_lengths, decoder.stats.bytes_skipped) == (1, 4)


def config(fingerprint: int):
    return make_frame(
        "CONFIG", 0, protocol_version=1, schema_fingerprint=fingerprint, fw_major=1, fw_minor=2, fw_patch=3,
        accel_fs_g=8, gyro_fs_dps=500, rate_hz=100, mode=0, mounting=0, gyro_calibration=1,
    )


def test_config_from_firmware_built_from_another_spec_is_reported():
    decoder = StreamDecoder()
    assert decoder.schema_matches is None
    decoder.feed(encode(config(SPEC.fingerprint)))
    assert decoder.schema_matches is True and decoder.stats.schema_mismatches == 0
    decoder.feed(encode(config(SPEC.fingerprint ^ 1)))
    assert decoder.schema_matches is False and decoder.stats.schema_mismatches == 1

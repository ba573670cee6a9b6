"""The decode a piece of the stream at a time (``PieceDecoder``, ``decode_pieces``) against the decode of the
whole stream at once, which tests/protocol/test_batch.py holds to the incremental ``StreamDecoder``.

Joined, the pieces must be the whole decode exactly: every frame column bit for bit (order, seq, raw
payload bytes, device time, chunk, arrival), the counters after every chunk and at the end, the pending
tail, the rate and the schema fingerprint. Piece boundaries fall everywhere: after every chunk (each
frame its own chunk: after a frame the rules hold, before the frame that confirms it), inside frames
(chunks that split them), inside garbage and duplicates, at reboots and gaps, and at the default size.
"""

import random

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from firmware_protocol import SPEC, encode, make_frame
from firmware_protocol.batch import CHUNK_COUNTERS, PIECE_BYTES, decode_chunks, decode_pieces, joined, pieces_of

from tests.simulated import simulated_chunks

from .strategies import any_frame
from .test_batch import FATES, SENSORS, assert_mishaps_decoded, chunked, damaged_stream, imu, numbered


def assert_same_decode(got, whole) -> None:
    assert list(got.frames) == list(whole.frames)
    for name, expected in whole.frames.items():
        columns = got.frames[name]
        for field in ("order", "seq", "chunk", "t_host_ns"):
            assert np.array_equal(getattr(columns, field), getattr(expected, field)), (name, field)
            assert getattr(columns, field).dtype == getattr(expected, field).dtype, (name, field)
        assert columns.raw.dtype == expected.raw.dtype and columns.raw.tobytes() == expected.raw.tobytes(), name
        if expected.device_time_us is None:
            assert columns.device_time_us is None
        else:
            assert np.array_equal(columns.device_time_us, expected.device_time_us), name
    assert got.stats == whole.stats
    assert (got.pending_bytes, got.remote_fingerprint, got.rate_hz) == (whole.pending_bytes, whole.remote_fingerprint, whole.rate_hz)
    assert np.array_equal(got.chunk_t_host_ns, whole.chunk_t_host_ns)
    for counter in CHUNK_COUNTERS:
        assert np.array_equal(got.chunk_counters[counter], whole.chunk_counters[counter]), counter


def assert_pieces_same(chunks, piece_sizes=(1, 7, 300, PIECE_BYTES)):
    """Decoded whole, then in pieces of whole chunks of at least each size (1: every chunk a piece)."""
    whole = decode_chunks(chunks)
    for piece_bytes in piece_sizes:
        assert_same_decode(decode_chunks(chunks, piece_bytes=piece_bytes), whole)
    return whole


def test_each_piece_says_the_counters_after_its_last_chunk():
    chunks = simulated_chunks(4.0, loss=0.05, ber=3e-4, reboot_after_s=2.0, **SENSORS)
    whole = decode_chunks(chunks)
    chunks_before = 0
    for piece in decode_pieces(pieces_of(chunks, 500)):
        chunks_before += len(piece.chunk_t_host_ns)
        for counter in CHUNK_COUNTERS:
            assert getattr(piece.stats, counter) == whole.chunk_counters[counter][chunks_before - 1]
    assert chunks_before == len(chunks) and piece.stats == whole.stats


def test_one_frame_a_piece_across_reboots_gaps_garbage_and_duplicates():
    """Each frame its own chunk and piece: a reboot's first frame is held at the end of one piece and
    confirmed by the first frame of the next; a gap of lost frames, a long outage, a duplicate and
    garbage with sync bytes each fall on a boundary."""
    rng = random.Random(35)
    frames, t_us = [], 1_000_000
    for i in range(1500):
        t_us = 7 if i == 500 else t_us + 10_000  # a reboot
        frames.append(imu(i, t_us))
    frames[200:230] = []  # a gap of lost frames
    frames[1200:1500] = [imu(i + 4000, f.values["t_us"] + 40_000_000) for i, f in enumerate(frames[1200:1500])]  # an outage
    parts = []
    for k, frame in enumerate(frames):
        data = encode(frame)
        if k % 97 == 0:
            data += data  # a duplicate
        if k % 53 == 0:
            data = bytes([SPEC.sync, 3]) + rng.randbytes(rng.randint(0, 20)) + data  # garbage with sync bytes
        parts.append(data)
    chunks = [(10_000_000 * k + (40_000_000_000 if k >= 1200 else 0), data) for k, data in enumerate(parts)]
    whole = assert_pieces_same(chunks)
    assert whole.stats.restarts == 1 and whole.stats.frames_lost > 4000 and whole.stats.duplicates > 10
    # and every frame split across two pieces
    halves = [half for t, data in chunks for half in ((t, data[: len(data) // 2]), (t + 1, data[len(data) // 2 :]))]
    assert_pieces_same(halves, (1, 50))


def test_simulated_sessions_with_reboots_clock_jumps_and_a_bad_link():
    assert_mishaps_decoded(assert_pieces_same, 6.0)


def test_a_held_frame_decided_several_pieces_later():
    """A frame stamped far ahead is held; frames without timestamp (CONFIG) come in the pieces after it,
    then a timestamped frame that does not follow it: it was noise."""
    config = SPEC.frame("CONFIG")
    values = {f.name: 1 for f in config.fields} | {"rate_hz": 100}
    stream = [imu(i, 10_000 * i) for i in range(100)]
    stream += [imu(100, 900_000_000), *(make_frame("CONFIG", 101 + k, **values) for k in range(3)), imu(104, 10_000 * 104)]
    stream += [imu(i, 10_000 * i) for i in range(105, 200)]
    whole = assert_pieces_same([(1_000 * k, encode(f)) for k, f in enumerate(stream)])
    assert whole.stats.implausible == 1


def test_empty_and_tiny_streams():
    assert_pieces_same([])
    assert_pieces_same([(5, b"")])
    assert_pieces_same([(5, encode(imu(0, 0))[:3]), (6, b""), (7, encode(imu(0, 0))[3:])])


@settings(max_examples=60, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(any_frame, min_size=1, max_size=60),
    st.lists(st.sampled_from(FATES), min_size=60, max_size=60),
    st.lists(st.binary(min_size=1, max_size=40), min_size=60, max_size=60),
    st.randoms(use_true_random=False),
    st.integers(1, 64),
    st.integers(1, 400),
)
def test_damaged_streams_in_any_pieces(frames, fates, noises, rng, max_chunk, piece_bytes):
    stream = damaged_stream(numbered(frames, rng.randrange(256)), fates, noises, rng)
    assert_pieces_same(chunked(stream, rng, max_chunk), (1, piece_bytes))


def test_the_pieces_are_let_go_as_they_are_joined():
    """``joined`` holds the whole decode and one column's pieces beside it, not every piece beside the whole
    (twice the decode): the pieces' arrays go as each column is joined. tracemalloc counts numpy's arrays."""
    import tracemalloc

    chunks = simulated_chunks(20.0, **SENSORS)
    tracemalloc.start()
    try:
        pieces = list(decode_pieces(pieces_of(chunks, 16_384)))
        before = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        got = joined(pieces)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    whole = sum(a.nbytes for c in got.frames.values() for a in (c.order, c.seq, c.raw, c.device_time_us, c.chunk, c.t_host_ns)
                if a is not None) + got.chunk_t_host_ns.nbytes + sum(a.nbytes for a in got.chunk_counters.values())
    assert len(pieces) > 5
    assert peak - before < whole / 4, (peak - before, whole)
    assert_same_decode(got, decode_chunks(chunks))

"""Columnar decode of a whole recorded byte stream: numpy arrays per frame type, no Frame objects.

``decode_batch(data, chunk_ends, chunk_t_host_ns)`` gives exactly what ``StreamDecoder`` gives when
fed the same bytes chunk by chunk (the same frames, device times, counters, pending tail), as
columns. The incremental decoder's decisions do not depend on the chunking (it waits for a whole
frame before deciding), so the batch decode is the incremental rules restated over the whole buffer:

1. Every sync byte is a candidate. Its length byte is checked against its type, and the CRC of every
   candidate whose header is plausible is computed at once (a byte-table CRC-16/CCITT-FALSE over
   the candidates as columns: one numpy pass per frame byte, not per frame).
2. The incremental decoder accepts a CRC-valid candidate when it starts at or after the end of the
   frame accepted before it (its scan resumes at that end), and examines, then skips, every other
   sync byte outside accepted frames. CRC-valid candidates overlap only around damage (a frame that
   happens to pass the CRC inside another); only those clusters are resolved by a Python loop.
3. Duplicates, sequence gaps, the 32-bit device-time unwrap and the CONFIG fingerprint are
   sequence rules over the accepted frames in stream order: array operations, with Python only for
   the rare consecutive frames whose sequence numbers are equal (the duplicate rule compares the
   unpacked values exactly as the incremental decoder does).

Payloads are unpacked by viewing the frames' bytes as a numpy structured dtype built from the spec
(``payload_dtype``), so the raw values are the wire values, bit for bit. Each frame also gets the
host arrival time of the chunk with which the incremental path returns it: the chunk holding its
last byte, or a later one when a damaged header before it announced a frame longer than the bytes
that had arrived (the incremental decoder waits for those bytes before it can go on).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from firmware_protocol.codec import CRC_BYTES, FRAME_TYPES_BY_ID, HEADER_BYTES, SYNC
from firmware_protocol.decoder import DecoderStats
from firmware_protocol.spec import C_TYPES, SPEC, FrameType

_OVERHEAD = HEADER_BYTES + CRC_BYTES
_CONFIG = SPEC.frame("CONFIG")
_TYPES = [FRAME_TYPES_BY_ID.get(i) for i in range(256)]
# Per type id (0..255): payload size, -1 for ids the spec lacks (any length up to the maximum is plausible).
_SIZE = np.array([t.payload_size if t else -1 for t in _TYPES], dtype=np.int16)
_KNOWN = _SIZE >= 0
_TIMESTAMPED = np.array([bool(t and t.has_timestamp) for t in _TYPES])


def payload_dtype(frame_type: FrameType) -> np.dtype:
    """The packed little-endian numpy dtype of a frame type's payload, field for field from the spec."""
    return np.dtype([(f.name, "<" + C_TYPES[f.c_type][0]) for f in frame_type.fields])


def _crc_tables() -> tuple[np.ndarray, np.ndarray]:
    """CRC-16/CCITT-FALSE (poly 0x1021, no reflection) from a zero register of each byte value, and
    of each 16-bit word (high byte first). A 16-bit register is shifted out entirely by 16 bits of
    input, so a register ``c`` followed by a word ``w`` becomes ``T16[c ^ w]``: two bytes per step."""
    table = np.arange(256, dtype=np.uint32) << 8
    for _ in range(8):
        table = np.where(table & 0x8000, (table << 1) ^ 0x1021, table << 1) & 0xFFFF
    words = np.arange(65536, dtype=np.uint32)
    first = table[words >> 8]
    return table.astype(np.uint16), (((first << 8) & 0xFFFF) ^ table[(first >> 8) ^ (words & 0xFF)]).astype(np.uint16)


_CRC8, _CRC16 = _crc_tables()


@dataclass
class FrameColumns:
    """The frames of one type, in stream order."""

    type: FrameType
    order: np.ndarray  # int64: position of each frame among all frames returned (every type)
    seq: np.ndarray  # uint8
    raw: np.ndarray  # structured array, payload_dtype(type): wire values as sent
    device_time_us: np.ndarray | None  # int64, unwrapped; None for types without t_us
    t_host_ns: np.ndarray  # int64: arrival time of the chunk with which StreamDecoder returns the frame

    def __len__(self) -> int:
        return len(self.seq)

    def scaled(self, field: str) -> np.ndarray:
        """One field's physical values (raw * scale, in the spec's unit) as float64, as Frame.scaled."""
        (spec_field,) = (f for f in self.type.fields if f.name == field)
        return self.raw[field].astype(np.float64) * spec_field.scale


@dataclass
class BatchDecode:
    frames: dict[str, FrameColumns]  # by frame type name; every type of the spec, possibly empty
    stats: DecoderStats
    remote_fingerprint: int | None  # from the last CONFIG, as StreamDecoder.remote_fingerprint
    pending_bytes: int  # the incomplete tail the incremental decoder would still be waiting on


def decode_chunks(chunks: Iterable[tuple[int, bytes]]) -> BatchDecode:
    """``decode_batch`` of ``(t_host_ns, data)`` chunks as a recording holds them."""
    times, parts = [], []
    for t_host_ns, data in chunks:
        times.append(t_host_ns)
        parts.append(data)
    ends = np.cumsum([len(p) for p in parts], dtype=np.int64)
    return decode_batch(b"".join(parts), ends, np.array(times, dtype=np.int64))


def decode_batch(data: bytes, chunk_ends=None, chunk_t_host_ns=None) -> BatchDecode:
    """Decode ``data``, the concatenation of chunks ending at byte offsets ``chunk_ends`` (cumulative,
    exclusive) that arrived at ``chunk_t_host_ns``. Without chunks the arrival times are all 0."""
    buf = np.frombuffer(data, dtype=np.uint8)
    n = len(buf)
    if chunk_ends is None:
        chunk_ends, chunk_t_host_ns = np.array([n], dtype=np.int64), np.zeros(1, dtype=np.int64)
    starts, ends, ready, stop, bad_lengths, crc_errors = _accepted_frames(buf)
    pending = n - stop
    frame_bytes = int((ends - starts).sum())
    # Every byte before the stop is in an accepted frame or skipped (StreamDecoder's accounting).
    stats = DecoderStats(bytes_in=n, frame_bytes=frame_bytes, bytes_skipped=stop - frame_bytes)
    stats.bad_lengths, stats.crc_errors = bad_lengths, crc_errors

    type_ids = buf[starts + 2].astype(np.intp)
    seqs = buf[starts + 3]
    duplicate = _duplicates(data, starts, ends, type_ids, seqs)
    stats.duplicates = int(duplicate.sum())
    keep = ~duplicate
    starts, ready, type_ids, seqs = starts[keep], ready[keep], type_ids[keep], seqs[keep]
    if len(seqs) > 1:
        stats.frames_lost = int(((np.diff(seqs.astype(np.int64)) - 1) & 0xFF).sum())
    known = _KNOWN[type_ids]
    stats.unknown_types = int((~known).sum())
    starts, ready, type_ids, seqs = starts[known], ready[known], type_ids[known], seqs[known]
    stats.frames = len(starts)

    device_time = _unwrap(buf, starts, _TIMESTAMPED[type_ids])
    chunk_index = np.searchsorted(np.asarray(chunk_ends), ready - 1, side="right")
    t_host = np.asarray(chunk_t_host_ns, dtype=np.int64)[chunk_index]
    frames = {}
    for frame_type in SPEC.frames:
        (order,) = np.nonzero(type_ids == frame_type.id)
        dtype = payload_dtype(frame_type)
        if len(order):  # a frame's payload lies within the buffer, so its window exists
            rows = np.lib.stride_tricks.sliding_window_view(buf, frame_type.payload_size)[starts[order] + HEADER_BYTES]
            raw = np.ascontiguousarray(rows).view(dtype).reshape(len(order))
        else:
            raw = np.zeros(0, dtype)
        frames[frame_type.name] = FrameColumns(
            frame_type, order, seqs[order], raw, device_time[order] if frame_type.has_timestamp else None, t_host[order]
        )
    remote = None
    configs = frames[_CONFIG.name].raw
    if len(configs):
        fingerprints = configs["schema_fingerprint"]
        stats.schema_mismatches = int((fingerprints != SPEC.fingerprint).sum())
        remote = int(fingerprints[-1])
    return BatchDecode(frames, stats, remote, pending)


def _candidates(buf: np.ndarray):
    """Every sync byte with its verdict: plausible length, complete, CRC-valid; and frame ends."""
    n = len(buf)
    syncs = np.flatnonzero(buf == SYNC)
    header = syncs + HEADER_BYTES <= n
    lengths = np.zeros(len(syncs), dtype=np.int64)
    sizes = np.full(len(syncs), -1, dtype=np.int64)
    lengths[header] = buf[syncs[header] + 1]
    sizes[header] = _SIZE[buf[syncs[header] + 2]]
    plausible = header & ((lengths == sizes) | ((sizes < 0) & (lengths <= SPEC.max_payload_bytes)))
    ends = syncs + _OVERHEAD + lengths
    complete = plausible & (ends <= n)
    valid = np.zeros(len(syncs), dtype=bool)
    for length in np.flatnonzero(np.bincount(lengths[complete])):
        (which,) = np.nonzero(complete & (lengths == length))
        valid[which] = _crc_is_zero(buf, syncs[which] + 1, int(length) + _OVERHEAD - 1)
    return syncs, header, plausible, complete, valid, ends


def _crc_is_zero(buf: np.ndarray, body_starts: np.ndarray, body_bytes: int) -> np.ndarray:
    """CRC over ``body_bytes`` from each start (CRC included) is zero: the frame is intact."""
    rows = np.lib.stride_tricks.sliding_window_view(buf, body_bytes)[body_starts]
    crc = np.full(len(body_starts), 0xFFFF, dtype=np.uint16)
    if body_bytes % 2:  # an odd byte first, then whole words
        crc = (crc << 8) ^ _CRC8[(crc >> 8) ^ rows[:, 0]]
        rows = rows[:, 1:]
    # One contiguous row of big-endian words per word position.
    words = np.ascontiguousarray(np.ascontiguousarray(rows).view(">u2").astype(np.uint16).T)
    for word in words:
        crc = _CRC16[crc ^ word]
    return crc == 0


def _accepted_frames(buf: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int, int]:
    """Starts and ends of the frames the incremental decoder accepts, and how many bytes it needs
    before it returns each (at least its end); where its scan stops
    (``len(buf)`` unless it waits on an incomplete candidate at the end); and the bad lengths and
    CRC failures among the sync bytes it examined and gave up on the way."""
    syncs, header, plausible, complete, valid, ends = _candidates(buf)
    s, e = syncs[valid], ends[valid]
    accepted = _greedy(s, e)
    s, e = s[accepted], e[accepted]
    # Sync bytes inside accepted frames are never examined. The scan stops at the first examined one
    # that lacks its header, or has a plausible length but not all its bytes yet.
    examined = ~_inside(syncs, s, e)
    waiting = examined & (~header | (plausible & ~complete))
    stop = len(buf)
    if waiting.any():
        stop = int(syncs[np.argmax(waiting)])
        keep = s < stop
        s, e = s[keep], e[keep]
        examined &= syncs < stop
    bad_lengths = int((examined & header & ~plausible).sum())
    crc_errors = int((examined & complete & ~valid).sum())
    # A frame comes out once the scan has decided every candidate before it, and some of those need
    # bytes beyond the frame's end (a damaged header announcing a longer frame than follows).
    needed = np.where(plausible, ends, syncs + HEADER_BYTES)[examined]
    before = np.searchsorted(syncs[examined], s)
    ready = e.copy()
    if len(needed):
        reach = np.maximum.accumulate(needed)
        has_before = before > 0
        ready[has_before] = np.maximum(e[has_before], reach[before[has_before] - 1])
    return s, e, ready, stop, bad_lengths, crc_errors


def _greedy(s: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Which CRC-valid candidates (sorted starts ``s``, ends ``e``) are accepted: each one that starts
    at or after the end of the last accepted one, where the incremental scan resumes.

    A candidate starting at or after every earlier end is accepted whatever came before; only the
    others (a CRC-valid candidate inside another frame: damage) need the sequential rule.
    """
    accepted = np.ones(len(s), dtype=bool)
    if len(s) < 2:
        return accepted
    reach = np.maximum.accumulate(e)
    fresh = np.concatenate(([True], s[1:] >= reach[:-1]))
    last_fresh = np.maximum.accumulate(np.where(fresh, np.arange(len(s)), 0))
    last_overlapping_accepted = -1
    for i in np.flatnonzero(~fresh).tolist():
        last = max(int(last_fresh[i]), last_overlapping_accepted)
        if s[i] >= e[last]:
            last_overlapping_accepted = i
        else:
            accepted[i] = False
    return accepted


def _inside(positions: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Whether each position lies within one of the sorted, disjoint [start, end) intervals."""
    if not len(starts):
        return np.zeros(len(positions), dtype=bool)
    i = np.searchsorted(starts, positions, side="right") - 1
    return (i >= 0) & (positions < ends[np.maximum(i, 0)])


def _duplicates(data: bytes, starts, ends, type_ids, seqs) -> np.ndarray:
    """StreamDecoder's rule: same seq and equal unpacked values as the last non-duplicate frame."""
    duplicate = np.zeros(len(starts), dtype=bool)
    if len(starts) < 2:
        return duplicate
    unpackers = {t.id: t.struct.unpack_from for t in SPEC.frames}

    def raw(i):
        unpack = unpackers.get(int(type_ids[i]))
        return unpack(data, int(starts[i]) + HEADER_BYTES) if unpack else data[starts[i] : ends[i]]

    reference = {}  # frame -> the last non-duplicate before it, for runs of repeats
    for i in (np.flatnonzero(seqs[1:] == seqs[:-1]) + 1).tolist():
        previous = reference.get(i - 1, i - 1) if duplicate[i - 1] else i - 1
        if raw(i) == raw(previous):
            duplicate[i] = True
            reference[i] = previous
    return duplicate


def _unwrap(buf: np.ndarray, starts: np.ndarray, timestamped: np.ndarray) -> np.ndarray:
    """64-bit device time of every timestamped frame (0 elsewhere): each step is the signed 32-bit
    difference from the previous timestamped frame of any type, as in StreamDecoder."""
    out = np.zeros(len(starts), dtype=np.int64)
    at = starts[timestamped] + HEADER_BYTES
    if len(at):
        # TIMESTAMP_FIELD is the first field: a little-endian uint32 at the payload's start.
        t32 = np.lib.stride_tricks.sliding_window_view(buf, 4)[at].copy().view("<u4").reshape(-1).astype(np.int64)
        step = np.diff(t32) & 0xFFFFFFFF
        step[step >= 0x80000000] -= 0x100000000
        out[timestamped] = t32[0] + np.concatenate(([0], np.cumsum(step)))
    return out

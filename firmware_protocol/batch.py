"""Columnar decode of a whole recorded byte stream: numpy arrays per frame type, no Frame objects.

``decode_chunks(chunks)`` gives exactly what ``StreamDecoder`` gives when fed the same ``(t_host_ns,
bytes)`` chunks one by one (the same frames in the same order, device times, the chunk each frame
comes out with, counters, pending tail), as columns; and the counters as they stood after every
chunk (what the link's per-second figures read). The incremental decoder waits for a whole frame
before it decides on it, so framing does not depend on the chunking, and the decode is done in two
passes over the whole buffer:

1. Framing, as array operations. Every sync byte is a candidate; its length byte is checked against
   its type and the CRC of every plausible one is computed at once (a table CRC-16/CCITT-FALSE over
   the candidates as columns: one numpy pass per two frame bytes, not per frame). The scan accepts a
   CRC-valid candidate that starts at or after the end of the frame accepted before it, and examines,
   then skips, every other sync byte outside accepted frames; CRC-valid candidates overlap only
   around damage (a frame that passes the CRC inside another), and only those are resolved in Python.
   Where the scan stood after each chunk follows from the bytes each examined candidate needs.
2. Sequence and time. Duplicates (same seq and values as the frame before) and unknown types are
   dropped; then every frame that the incremental decoder's fast path takes (a timestamped frame
   with the next seq, soon after a timestamped one) is placed by a cumulative sum, and every other
   frame by the rules the incremental decoder calls for it (``decoder.SequenceRules``: ``timed`` and
   ``untimed``): the first frame, frames without timestamp, gaps, long or backward steps, held frames
   and restarts. One set of rules, no copy of them here.

Payloads are unpacked by viewing the frames' bytes as a numpy structured dtype built from the spec
(``payload_dtype``), so raw values are the wire values, bit for bit.

A piece at a time. ``PieceDecoder`` runs these passes over consecutive pieces of whole chunks (``decode_batch``
is one piece: the whole), carrying between them what ``StreamDecoder`` carries between chunks: the tail the
scan stopped at, the last frame for the duplicate rule, the ``SequenceRules`` (whose counters are the
decoder's) and the bytes of the frame they hold, which leads the next piece; ``decode_pieces`` and
``joined`` give the whole stream's result from the pieces', bit for bit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from firmware_protocol.codec import CRC_BYTES, HEADER_BYTES, SYNC
from firmware_protocol.decoder import DecoderStats, SequenceRules
from firmware_protocol.spec import C_TYPES, SPEC, FrameType, Spec

_OVERHEAD = HEADER_BYTES + CRC_BYTES
_CONFIG = SPEC.frame("CONFIG")
# DecoderStats as they stood after each chunk: what link.LinkStats reads per second.
CHUNK_COUNTERS = ("frames", "bytes_in", "crc_errors", "frames_lost", "bytes_skipped")


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
    """The frames of one type, in the order the incremental decoder returns them."""

    type: FrameType
    order: np.ndarray  # int64: position of each frame among all frames returned (every type)
    seq: np.ndarray  # uint8
    raw: np.ndarray  # structured array, payload_dtype(type): wire values as sent
    device_time_us: np.ndarray | None  # int64, unwrapped as StreamDecoder does; None for types without t_us
    chunk: np.ndarray  # int64: index of the chunk with which StreamDecoder returns the frame
    t_host_ns: np.ndarray  # int64: that chunk's arrival time

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
    remote_fingerprint: int | None  # as StreamDecoder.remote_fingerprint after the last chunk
    rate_hz: int  # as StreamDecoder.rate_hz
    pending_bytes: int  # the incomplete tail the incremental decoder would still be waiting on
    chunk_t_host_ns: np.ndarray  # (chunks,) arrival times
    chunk_counters: dict[str, np.ndarray]  # CHUNK_COUNTERS -> (chunks,): each counter after each chunk

    @property
    def count(self) -> int:
        return self.stats.frames


PIECE_BYTES = 1 << 21  # link bytes decoded at once by ``decode_pieces`` (~2 min of a 100 Hz flight with sensors)


def decode_chunks(chunks: Iterable[tuple[int, bytes]], spec: Spec = SPEC,
                  progress: Callable[[int, int], None] | None = None, piece_bytes: int | None = None) -> BatchDecode:
    """``decode_batch`` of ``(t_host_ns, data)`` chunks as a recording holds them; ``piece_bytes``: decoded
    that many bytes at a time (``decode_pieces``) and joined, the same result (None: at once)."""
    if piece_bytes is not None:
        return joined(decode_pieces(pieces_of(chunks, piece_bytes), spec))
    times, parts = [], []
    for t_host_ns, data in chunks:
        times.append(t_host_ns)
        parts.append(data)
    ends = np.cumsum([len(p) for p in parts], dtype=np.int64)
    return decode_batch(b"".join(parts), ends, np.array(times, dtype=np.int64), spec, progress)


def decode_batch(data: bytes, chunk_ends=None, chunk_t_host_ns=None, spec: Spec = SPEC,
                 progress: Callable[[int, int], None] | None = None) -> BatchDecode:
    """Decode ``data``, the concatenation of chunks ending at byte offsets ``chunk_ends`` (cumulative,
    exclusive) that arrived at ``chunk_t_host_ns``. Without chunks: one chunk arriving at 0.
    ``progress(done, total)`` is told the frames placed so far."""
    return PieceDecoder(spec).decode(data, chunk_ends, chunk_t_host_ns, progress)


def pieces_of(chunks: Iterable[tuple[int, bytes]], piece_bytes: int) -> Iterator[tuple[bytes, np.ndarray, np.ndarray]]:
    """``(t_host_ns, data)`` chunks grouped into pieces of whole chunks of at least ``piece_bytes`` (but the
    last): ``(data, chunk_ends, chunk_t_host_ns)`` each, as ``PieceDecoder.decode`` takes them. No chunks: one
    empty piece."""
    times: list[int] = []
    parts: list[bytes] = []
    size = 0
    handed = False
    for t_host_ns, data in chunks:
        times.append(t_host_ns)
        parts.append(data)
        size += len(data)
        if size >= piece_bytes:
            yield b"".join(parts), np.cumsum([len(p) for p in parts], dtype=np.int64), np.array(times, dtype=np.int64)
            times, parts, size, handed = [], [], 0, True
    if parts or not handed:
        yield b"".join(parts), np.cumsum([len(p) for p in parts], dtype=np.int64), np.array(times, dtype=np.int64)


def decode_pieces(pieces: Iterable[tuple[bytes, np.ndarray, np.ndarray]], spec: Spec = SPEC) -> Iterator[BatchDecode]:
    """``PieceDecoder.decode`` of each piece in turn (``pieces_of``; ``Recording.pieces``)."""
    decoder = PieceDecoder(spec)
    for data, chunk_ends, chunk_t_host_ns in pieces:
        yield decoder.decode(data, chunk_ends, chunk_t_host_ns)


def joined(pieces: Iterable[BatchDecode]) -> BatchDecode:
    """The pieces of one stream (``decode_pieces``) as one ``BatchDecode``: that of the whole stream. The pieces
    are emptied as they are joined, a column at a time (memory: the whole decode and one column's pieces, not
    every piece beside the whole)."""
    pieces = list(pieces)
    last = pieces[-1]
    frames = {}
    for name in list(last.frames):
        parts = [p.frames.pop(name) for p in pieces]
        fields = {}
        for field in ("order", "seq", "raw", "device_time_us", "chunk", "t_host_ns"):
            if getattr(parts[0], field) is None:  # a type without device time
                fields[field] = None
                continue
            fields[field] = np.concatenate([getattr(c, field) for c in parts])
            for c in parts:
                setattr(c, field, None)
        frames[name] = FrameColumns(parts[0].type, **fields)
        del parts
    counters = {}
    for c in CHUNK_COUNTERS:
        counters[c] = np.concatenate([p.chunk_counters.pop(c) for p in pieces])
    chunk_t_host_ns = np.concatenate([p.chunk_t_host_ns for p in pieces])
    return BatchDecode(frames, last.stats, last.remote_fingerprint, last.rate_hz, last.pending_bytes, chunk_t_host_ns, counters)


@dataclass
class _Previous:
    """The last kept frame of the pieces decoded so far: whether the next one continues a fast run."""

    timestamped: bool
    seq: int
    t32: int


class PieceDecoder:
    """The decode a piece of the stream at a time: each ``decode`` takes the chunks that follow those of the
    one before and returns their frames (``order`` and ``chunk`` counted from the stream's start), the
    counters after each of its chunks, and the counters and state after its last, exactly as a decode of
    the whole stream would (``StreamDecoder`` likewise fed chunk by chunk). Carried from piece to piece,
    as ``StreamDecoder`` carries them from chunk to chunk: the undecided tail (``pending``), the last frame
    for the duplicate rule, ``SequenceRules`` (the counters it keeps in ``stats``) and the frame it holds,
    whose bytes are kept and which comes out with the piece that confirms it."""

    def __init__(self, spec: Spec = SPEC) -> None:
        self.spec = spec
        self.tables = _Tables(spec)
        self.stats = DecoderStats()
        self.rules = SequenceRules(self.stats, spec)
        self.pending = b""
        self.held = b""  # the bytes of the frame ``rules.held`` is, when it holds one
        self.last_frame: tuple[int, tuple] | None = None  # (seq, raw values): the duplicate rule's last frame
        self.previous: _Previous | None = None
        self.chunks = 0  # chunks decoded so far

    def decode(self, data: bytes, chunk_ends=None, chunk_t_host_ns=None,
               progress: Callable[[int, int], None] | None = None) -> BatchDecode:
        """The next piece: ``data``, its chunks ending at ``chunk_ends`` (cumulative within ``data``) and
        arriving at ``chunk_t_host_ns`` (without chunks: one arriving at 0); ``progress(done, total)`` is
        told the piece's frames placed so far."""
        new_bytes = len(data)
        if chunk_ends is None:
            chunk_ends, chunk_t_host_ns = np.array([new_bytes], dtype=np.int64), np.zeros(1, dtype=np.int64)
        chunk_t_host_ns = np.asarray(chunk_t_host_ns, dtype=np.int64)
        spec, tables, stats = self.spec, self.tables, self.stats
        # The held frame, then the tail the scan stopped at, then the piece: one buffer, positions within it.
        held = len(self.held)
        before = held + len(self.pending)
        if before:
            data = self.held + self.pending + bytes(data)
        buf = np.frombuffer(data, dtype=np.uint8)
        chunk_ends = before + np.asarray(chunk_ends, dtype=np.int64)
        scan = _scan(buf[held:], chunk_ends - held, tables, spec)
        scan.shift(held)
        starts = scan.starts
        type_ids = buf[starts + 2].astype(np.intp)
        seqs = buf[starts + 3]
        duplicate, self.last_frame = _duplicates(data, starts, type_ids, seqs, tables, self.last_frame)
        known = tables.known[type_ids]
        keep = ~duplicate & known
        kept_starts = starts[keep]
        if held:  # the held frame leads: kept index 0
            kept_starts = np.concatenate(([0], kept_starts))
        kept = _Kept(buf, kept_starts, buf[kept_starts + 2].astype(np.intp), buf[kept_starts + 3], tables)
        duplicates, unknown_types = int(duplicate.sum()), int((~duplicate & ~known).sum())
        # Intermediates of an hour's frames are ~6 MB each: each goes once used (the decode's peak memory).
        del type_ids, seqs, duplicate, known, keep, kept_starts
        chunk_of = np.searchsorted(scan.stops, kept.starts, side="right")  # the chunk whose feed reaches the frame
        frames_before, lost_before = stats.frames, stats.frames_lost
        counters_before = {c: getattr(stats, c) for c in CHUNK_COUNTERS}
        placed = _sequence(data, kept, chunk_of, chunk_t_host_ns, tables, self.rules, frames_before + lost_before,
                           self.previous, bool(held), progress)
        if len(kept) > bool(held):
            last = len(kept) - 1
            self.previous = _Previous(bool(kept.timestamped[last]), int(kept.seqs[last]), int(kept.t32[last]))
        del kept.t32, kept.timestamped

        stops = scan.stops
        final = int(stops[-1]) if len(stops) else held
        frame_bytes = int((scan.ends - starts).sum())
        stats.bytes_in += new_bytes
        stats.frame_bytes += frame_bytes
        stats.bytes_skipped += final - held - frame_bytes  # the pending tail was left undecided by the piece before
        stats.bad_lengths += int(scan.bad_at.size)
        stats.crc_errors += int(scan.crc_at.size)
        stats.duplicates += duplicates
        stats.unknown_types += unknown_types
        stats.frames += len(placed.index)
        stats.frames_lost += int(placed.lost.sum())

        # Counters after each chunk: what lies before the scan's stop then.
        emitted_at = np.sort(kept.starts[placed.emitter])  # a held frame comes out with the frame that confirms it
        frame_ends = np.concatenate(([0], np.cumsum(scan.ends - starts)))
        counters = {
            "frames": frames_before + np.searchsorted(emitted_at, stops),
            "bytes_in": counters_before["bytes_in"] + chunk_ends - before,
            "crc_errors": counters_before["crc_errors"] + np.searchsorted(scan.crc_at, stops),
            "frames_lost": lost_before + np.concatenate(([0], np.cumsum(placed.lost)))[np.searchsorted(kept.starts, stops)],
            "bytes_skipped": counters_before["bytes_skipped"] + stops - held - frame_ends[np.searchsorted(starts, stops)],
        }
        del emitted_at, frame_ends, starts, placed.lost, scan

        self.held = b""
        if placed.held_at >= 0:  # its bytes wait for the piece that decides on it
            at = int(kept.starts[placed.held_at])
            self.held = bytes(data[at : at + _OVERHEAD + data[at + 1]])
        self.pending = bytes(data[final:])

        order_of = placed.index  # kept index of each frame returned, in return order
        returned_types = kept.type_ids[order_of]
        frames = {}
        for frame_type in spec.frames:
            (order,) = np.nonzero(returned_types == frame_type.id)
            which = order_of[order]
            dtype = payload_dtype(frame_type)
            starts = kept.starts[which]
            whole = buf[starts + 1] == frame_type.payload_size
            shorter = np.flatnonzero(~whole)  # an older sender's shorter payloads (rare: a few CONFIG frames)
            raw = np.zeros(len(which), dtype)
            if len(shorter) < len(which):  # a whole payload lies within the buffer, so its window exists
                rows = np.lib.stride_tricks.sliding_window_view(buf, frame_type.payload_size)[starts[whole] + HEADER_BYTES]
                wholes = np.ascontiguousarray(rows).view(dtype).reshape(-1)
                if len(shorter):
                    raw[whole] = wholes
                else:
                    raw = wholes
            for k in shorter.tolist():
                raw[k] = tables.read(data, int(starts[k]))
            chunk = chunk_of[placed.emitter[order]]
            device = placed.t64[order] if frame_type.has_timestamp else None
            frames[frame_type.name] = FrameColumns(frame_type, frames_before + order, kept.seqs[which], raw, device,
                                                   self.chunks + chunk, chunk_t_host_ns[chunk])
        self.chunks += len(chunk_ends)
        rules = self.rules
        return BatchDecode(frames, dataclasses.replace(stats), rules.remote_fingerprint, rules.rate_hz, len(self.pending),
                           chunk_t_host_ns, counters)


class _Tables:
    """Per type id (0..255) lookups from the spec."""

    def __init__(self, spec: Spec):
        by_id = {t.id: t for t in spec.frames}
        types = [by_id.get(i) for i in range(256)]
        self.types = types
        self.size = np.array([t.payload_size if t else -1 for t in types], dtype=np.int16)  # -1: unknown id
        self.known = self.size >= 0
        self.timestamped = np.array([bool(t and t.has_timestamp) for t in types])
        self.readers = [t.readers if t else None for t in types]  # payload length -> read (older senders' too)
        # [type id, length byte]: a length the frame type's payloads may have (any that fits, for an unknown id).
        self.accepts = np.zeros((256, 256), dtype=bool)
        for type_id, readers in enumerate(self.readers):
            if readers is None:
                self.accepts[type_id, : spec.max_payload_bytes + 1] = True
            else:
                self.accepts[type_id, list(readers)] = True

    def read(self, data: bytes, start: int) -> tuple:
        """The raw values of the known-type frame starting at ``start``, as ``StreamDecoder`` reads them."""
        return self.readers[data[start + 2]][data[start + 1]](data, start + HEADER_BYTES)


@dataclass
class _Scan:
    starts: np.ndarray  # accepted frames (CRC-valid, where the scan accepts them), sorted
    ends: np.ndarray
    stops: np.ndarray  # (chunks,) where the scan stood after each chunk: every byte before it is decided
    crc_at: np.ndarray  # sorted positions of candidates examined and failed (CRC)
    bad_at: np.ndarray  # ... with an impossible length

    def shift(self, offset: int) -> None:
        """Positions in a buffer that holds ``offset`` bytes before the scanned ones."""
        for name in ("starts", "ends", "stops", "crc_at", "bad_at"):
            setattr(self, name, getattr(self, name) + offset)


def _scan(buf: np.ndarray, chunk_ends: np.ndarray, tables: _Tables, spec: Spec) -> _Scan:
    n = len(buf)
    syncs = np.flatnonzero(buf == SYNC)
    header = syncs + HEADER_BYTES <= n
    lengths = np.zeros(len(syncs), dtype=np.int64)
    lengths[header] = buf[syncs[header] + 1]
    plausible = header & tables.accepts[buf[np.minimum(syncs + 2, n - 1)], lengths]
    ends = syncs + _OVERHEAD + lengths
    complete = plausible & (ends <= n)
    valid = np.zeros(len(syncs), dtype=bool)
    for length in np.flatnonzero(np.bincount(lengths[complete])):
        (which,) = np.nonzero(complete & (lengths == length))
        valid[which] = _crc_is_zero(buf, syncs[which] + 1, int(length) + _OVERHEAD - 1)
    s, e = syncs[valid], ends[valid]
    accepted = _greedy(s, e)
    s, e = s[accepted], e[accepted]
    del accepted, lengths  # an hour's candidates are ~6 MB an array: each goes once used (the decode's peak)
    # Sync bytes inside accepted frames are never examined. Each examined one, and each accepted frame,
    # needs bytes up to ``need`` before the scan can pass it: the scan stops after a chunk at the first
    # one needing more than has arrived (the chunk ends at or after the buffer's end: incomplete).
    examined = ~_inside(syncs, s, e)
    points = np.concatenate((syncs[examined], s))
    need = np.concatenate((np.where(plausible, ends, syncs + HEADER_BYTES)[examined], e))
    del ends
    ordering = np.argsort(points, kind="stable")
    points, need = points[ordering], need[ordering]
    del ordering
    reach = np.maximum.accumulate(need) if len(need) else need
    del need
    first_waiting = np.searchsorted(reach, chunk_ends, side="right")
    stops = chunk_ends.copy()
    waits = first_waiting < len(points)
    stops[waits] = np.minimum(points[first_waiting[waits]], chunk_ends[waits])
    final = int(stops[-1]) if len(stops) else n
    keep = s < final
    examined_decided = examined & (syncs < final)
    crc_at = syncs[examined_decided & complete & ~valid]
    bad_at = syncs[examined_decided & header & ~plausible]
    return _Scan(s[keep], e[keep], stops.astype(np.int64), crc_at, bad_at)


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


def _duplicates(data: bytes, starts, type_ids, seqs, tables: _Tables, last: tuple[int, tuple] | None):
    """StreamDecoder's rule: same seq and equal unpacked values as the last known-type non-duplicate frame
    (``last``: that of the stream before, (seq, values), or None). Returns which are duplicates, and the
    last known-type non-duplicate frame after them."""
    duplicate = np.zeros(len(starts), dtype=bool)
    known = tables.known[type_ids]
    # The rule compares with the last frame of a known type that was not a duplicate.
    index = np.flatnonzero(known)
    if not len(index):
        return duplicate, last
    ks = seqs[index]
    candidates = (np.flatnonzero(ks[1:] == ks[:-1]) + 1).tolist()
    if last is not None and int(ks[0]) == last[0]:
        candidates.insert(0, 0)
    for j in candidates:
        i, previous = int(index[j]), j - 1
        while previous >= 0 and duplicate[index[previous]]:
            previous -= 1
        earlier = last[1] if previous < 0 else tables.read(data, int(starts[index[previous]]))
        if tables.read(data, int(starts[i])) == earlier:
            duplicate[i] = True
    kept = index[~duplicate[index]]
    if len(kept):
        last = (int(seqs[kept[-1]]), tables.read(data, int(starts[kept[-1]])))
    return duplicate, last


class _Kept:
    """The frames that reach the sequence rules (known types, no duplicates), in stream order."""

    def __init__(self, buf: np.ndarray, starts, type_ids, seqs, tables: _Tables):
        self.starts, self.type_ids, self.seqs = starts, type_ids, seqs
        self.timestamped = tables.timestamped[type_ids]
        # TIMESTAMP_FIELD is the first field: a little-endian uint32 at the payload's start.
        at = starts + HEADER_BYTES
        t32 = np.zeros(len(starts), dtype=np.int64)
        if len(starts):
            t32 = np.lib.stride_tricks.sliding_window_view(buf, 4)[np.minimum(at, len(buf) - 4)].copy().view("<u4")
            t32 = t32.reshape(-1).astype(np.int64)
        self.t32 = np.where(self.timestamped, t32, 0)
        self.tables = tables

    def __len__(self) -> int:
        return len(self.starts)


@dataclass
class _Placed:
    index: np.ndarray  # kept index of each frame returned, in return order
    t64: np.ndarray  # its device time (0 for frames without timestamp)
    emitter: np.ndarray  # kept index of the frame whose processing returned it (a held frame: the confirming one)
    lost: np.ndarray  # (kept,) frames counted lost while processing each kept frame
    held_at: int  # kept index of the frame the rules hold after the last (-1: none)


def _sequence(data: bytes, kept: _Kept, chunk_of, chunk_t_host_ns, tables: _Tables, rules: SequenceRules, advanced: int,
              previous: _Previous | None, held_first: bool, progress) -> _Placed:
    """The sequence and time rules over the kept frames: fast runs as arrays, the rest through
    ``SequenceRules`` as the incremental decoder calls it. ``rules``: as the frames before left them;
    ``advanced``: the frames returned or counted lost before; ``previous``: the kept frame before the
    first (None: none); ``held_first``: the first kept frame is the one ``rules`` holds (decided already)."""
    n = len(kept)
    ts, seqs, t32 = kept.timestamped, kept.seqs.astype(np.int64), kept.t32
    # Frame j continues a fast run after frame j-1 if both are timestamped, seq follows and the step is short.
    if previous is None:
        previous = _Previous(False, 0, 0)
    before_ts, before_seqs, before_t32 = (np.concatenate(([v], a)) for v, a in
                                          ((previous.timestamped, ts), (previous.seq, seqs), (previous.t32, t32)))
    consecutive = ts & before_ts[:-1] & (seqs == (before_seqs[:-1] + 1) & 0xFF)
    step = (t32 - before_t32[:-1]) & 0xFFFFFFFF
    del before_ts, before_seqs, before_t32
    breaks_for: dict[int, np.ndarray] = {}
    index = np.empty(n, dtype=np.int64)
    t64 = np.zeros(n, dtype=np.int64)
    emitter = np.empty(n, dtype=np.int64)
    lost = np.zeros(n, dtype=np.int64)
    returned = 0
    lost_total = 0
    held_at = 0 if held_first else -1  # kept index of the held frame
    types = tables.types
    i = 1 if held_first else 0
    next_progress = 0
    while True:
        # The fast run from here: frames the incremental decoder's fast path takes.
        fast_us = rules.fast_us
        if fast_us and i < n:
            breaks = breaks_for.get(fast_us)
            if breaks is None:
                breaks = breaks_for[fast_us] = np.flatnonzero(~consecutive | (step >= fast_us))
            b = np.searchsorted(breaks, i)  # frame i - 1 is the reference: the run goes on to the next break
            end = int(breaks[b]) if b < len(breaks) else n
            if end > i and seqs[i] == rules.next_seq:
                steps = step[i:end]
                run = rules.t64 + np.cumsum(steps)
                count = end - i
                index[returned : returned + count] = np.arange(i, end)
                emitter[returned : returned + count] = index[returned : returned + count]
                t64[returned : returned + count] = run
                returned += count
                moved = np.flatnonzero(steps)
                # The reference moved in the chunk of the last frame that moved it.
                host_ns = int(chunk_t_host_ns[chunk_of[i + int(moved[-1])]]) if len(moved) else rules.host_ns
                rules.ran((int(seqs[end - 1]) + 1) & 0xFF, int(t32[end - 1]), int(run[-1]), host_ns)
                i = end
        if i >= n:
            break
        if progress is not None and i >= next_progress:
            progress(i, n)
            next_progress = i + 200_000
        type_id = int(kept.type_ids[i])
        seq = int(seqs[i])
        raw = tables.read(data, int(kept.starts[i]))
        t_host_ns = int(chunk_t_host_ns[chunk_of[i]])
        advances = advanced + returned + lost_total
        if not ts[i]:
            k = rules.untimed(type_id, seq, raw, advances)
            index[returned], emitter[returned] = i, i
            returned += 1
        else:
            out: list = []
            held_before = rules.held
            k = rules.timed(out, types[type_id], seq, raw, int(t32[i]), t_host_ns, advances)
            if len(out) == 2:
                index[returned], t64[returned], emitter[returned] = held_at, out[0][3], i
                returned += 1
            if out:
                index[returned], t64[returned], emitter[returned] = i, out[-1][3], i
                returned += 1
            if rules.held is not None and rules.held is not held_before:
                held_at = i
        lost[i] = k
        lost_total += k
        i += 1
    if progress is not None:
        progress(n, n)
    return _Placed(index[:returned], t64[:returned], emitter[:returned], lost, held_at if rules.held is not None else -1)

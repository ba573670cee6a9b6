"""Opening a recording: every intact record is recovered, every loss is described in ``damage``.

The file is mapped into memory (``mmap``: its pages are read as they are used and never copied)
and walked record by record with ``struct.unpack_from``; a record counts only if its marker, length
(at most ``MAX_PAYLOAD_BYTES``) and CRC-32 agree. Where they do not, the reader looks for the next
record that does (resynchronisation, ``search``: linear in the file size however many false markers
it holds) and reports the bytes in between. A file is identified from its first bytes: without the
recording's identification, an intact record must start within ``FIRST_RECORD_WITHIN_BYTES``, so a
huge foreign file is refused after reading only that much.
"""

from __future__ import annotations

import functools
import json
import mmap
import os
import stat
import zlib
from array import array
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from firmware_protocol.batch import pieces_of
from groundstation.recording import samples, search, sniff
from groundstation.recording.format import (
    CRC,
    FORMAT_VERSION,
    MAGIC,
    MARKER,
    MAX_PAYLOAD_BYTES,
    PREAMBLE,
    RECORD_HEADER,
    RECORD_OVERHEAD_BYTES,
    Kind,
    RecordingError,
)

HEADER_BYTES = RECORD_HEADER.size
INTACT_BLOCK_BYTES = 1 << 19  # ``_Walk.run_intact`` looks at the file this much at a time (memory: ~2x this)
MARKER_BYTES = len(MARKER)
# A recording whose identification (or first record) is damaged still has an intact record within
# one longest record of its start; a file without one there is not a recording.
FIRST_RECORD_WITHIN_BYTES = PREAMBLE.size + RECORD_OVERHEAD_BYTES + MAX_PAYLOAD_BYTES
# The writer stamps chunks with the host's monotonic clock, and nobody records for a year: a step
# forward beyond this between two chunks is damage (a crafted 2^62 ns step once hung the session).
MAX_CHUNK_STEP_NS = 365 * 24 * 3600 * 10**9


@dataclass
class Recording:
    """A recording read into memory. Chunks are served in file order (the order they arrived)."""

    path: Path
    version: int
    metadata: dict  # empty if the metadata record was lost (then ``damage`` says so)
    t_open_ns: int | None  # host monotonic clock when the writer opened the file (at metadata['start_utc'])
    events: list[tuple[int, dict]]  # (t_host_ns, event) in file order
    damage: list[str]  # human-readable findings; empty for an intact file
    closed_cleanly: bool  # the END record is there: the writer was not killed
    record_counts: dict[str, int]  # intact records: chunks, events, sample_blocks
    _buffer: mmap.mmap | bytes = field(repr=False)
    # int64 arrays ('q'), not lists: 24 bytes a chunk, where lists of ints took about 100
    _chunk_t_host_ns: array = field(repr=False)
    _chunk_offsets: array = field(repr=False)
    _chunk_lengths: array = field(repr=False)
    _sample_blocks: list[memoryview] = field(repr=False)  # the intact samples records' payloads

    @functools.cached_property
    def samples(self) -> dict[str, np.ndarray]:
        """Imported float64 columns, all blocks joined; empty if none. Decoded when first asked (they were
        checked at opening): a link recording's truth is read after its session is computed, not beside it."""
        return self.sample_columns()

    def sample_columns(self, names=None) -> dict[str, np.ndarray]:
        """``samples``, or only its columns ``names`` that it has, joined anew."""
        blocks = [samples.decode_block(payload) for payload in self._sample_blocks]
        names = list(blocks[0]) if blocks and names is None else [n for n in names or () if blocks and n in blocks[0]]
        joined = {name: np.concatenate([b[name] for b in blocks]) for name in names}
        release_pages(self._buffer)
        return joined

    @property
    def chunk_count(self) -> int:
        return len(self._chunk_offsets)

    @functools.cached_property
    def chunk_t_host_ns(self) -> np.ndarray:
        """int64 arrival times of all chunks, for seeking (``np.searchsorted``)."""
        return np.array(self._chunk_t_host_ns, dtype=np.int64)

    def chunk(self, index: int) -> tuple[int, bytes]:
        offset = self._chunk_offsets[index]
        return self._chunk_t_host_ns[index], self._buffer[offset:offset + self._chunk_lengths[index]]

    def stream(self) -> tuple[bytearray, np.ndarray, np.ndarray]:
        """Every chunk's bytes joined (a bytearray: one copy of them, no more), each chunk's end offset
        in them and its arrival time (the batch path)."""
        ends = np.cumsum(np.frombuffer(self._chunk_lengths, dtype=np.int64))
        data = bytearray(int(ends[-1]) if len(ends) else 0)
        into, source, start = memoryview(data), memoryview(self._buffer), 0
        for offset, length in zip(self._chunk_offsets, self._chunk_lengths):
            into[start:start + length] = source[offset:offset + length]
            start += length
        del into, source
        release_pages(self._buffer)
        return data, ends, self.chunk_t_host_ns

    def pieces(self, piece_bytes: int) -> Iterator[tuple[bytes, np.ndarray, np.ndarray]]:
        """``stream`` a piece at a time: consecutive whole chunks of at least ``piece_bytes`` (but the last)
        joined, their end offsets in the piece and arrival times (``firmware_protocol.batch.pieces_of``),
        the file's pages let go after each piece (``release_pages``): what this holds does not grow with
        the recording."""
        for piece in pieces_of(self.chunks(), piece_bytes):
            yield piece
            release_pages(self._buffer)

    def chunks(self, start: int = 0) -> Iterator[tuple[int, bytes]]:
        """(t_host_ns, data) from chunk index ``start`` on."""
        buffer = self._buffer
        for t_host_ns, offset, length in zip(
            self._chunk_t_host_ns[start:], self._chunk_offsets[start:], self._chunk_lengths[start:]
        ):
            yield t_host_ns, buffer[offset:offset + length]


def open_recording(path) -> Recording:
    """Reads ``path``; RecordingError only if nothing at all can be read (the message says why)."""
    path = Path(path)
    buffer = _map(path)
    damage: list[str] = []
    version, start = _read_preamble(path, buffer, damage)
    walk = _Walk(buffer)
    walk.run(walk.run_intact(start))
    walk.drop_repeats()
    damage += walk.damage + _chunk_time_jumps(walk.chunk_t_host_ns)
    if not walk.chunk_offsets and not walk.others:
        raise RecordingError(f"{path}: nothing could be read: " + "; ".join(damage))
    recording = _assemble(path, version, buffer, walk, damage)
    release_pages(buffer)
    return recording


def release_pages(buffer) -> None:
    """The file's pages that reading mapped into this process are let go (Linux, macOS): they stay in the
    kernel's cache and come back when read again, but no longer count in this process's memory, which the
    walk over every byte would otherwise grow by the file's size (bench/bench_export_memory.out.md)."""
    if isinstance(buffer, mmap.mmap) and hasattr(mmap, "MADV_DONTNEED"):
        buffer.madvise(mmap.MADV_DONTNEED)


def _map(path: Path) -> mmap.mmap | bytes:
    """The file's bytes, mapped read-only (an empty file, which cannot be mapped, as b"")."""
    try:
        with path.open("rb") as file:
            status = os.fstat(file.fileno())
            if not stat.S_ISREG(status.st_mode):  # /dev/zero would never end, a pipe never be mapped
                raise RecordingError(f"{path}: not a regular file (a device or a pipe), so not a recording")
            return mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ) if status.st_size else b""
    except FileNotFoundError:
        raise RecordingError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise RecordingError(f"{path}: is a folder, not a recording") from None
    except OSError as error:
        raise RecordingError(f"{path}: cannot be read ({error.strerror})") from None


def _read_preamble(path: Path, buffer, damage: list[str]) -> tuple[int, int]:
    """(format version, where the records start); raises for an empty, cut or foreign file."""
    if not buffer:
        raise RecordingError(f"{path} is empty (0 bytes): nothing was recorded")
    head = buffer[:len(MAGIC)]
    if MAGIC.startswith(head) and (head == MAGIC or len(buffer) < len(MAGIC)):
        if len(buffer) <= PREAMBLE.size:
            raise RecordingError(f"{path} ends inside its header ({len(buffer)} bytes): nothing was recorded")
        _, version = PREAMBLE.unpack_from(buffer)
        if 1 <= version <= FORMAT_VERSION:
            return version, PREAMBLE.size
        # The version field has no CRC of its own; the metadata record repeats it under its CRC.
        recorded = _recorded_format_version(buffer)
        if recorded is not None and 1 <= recorded <= FORMAT_VERSION:
            damage.append(f"format version field damaged (reads {version}); the metadata record says {recorded}")
            return recorded, PREAMBLE.size
        if version > FORMAT_VERSION:
            raise _newer_version_error(path, version)
        raise RecordingError(f"{path}: unreadable header (recording format version {version} does not exist)")
    # Not our identification. Recover the records if there are any (a damaged first block);
    # otherwise this is some other kind of file.
    first = _Walk(buffer).next_valid(0, stop=FIRST_RECORD_WITHIN_BYTES)
    if first is None:
        raise RecordingError(f"{path} is not a groundstation recording: it looks like {sniff.describe(buffer[:512])}")
    recorded = _recorded_format_version(buffer)
    if recorded is not None and recorded > FORMAT_VERSION:
        raise _newer_version_error(path, recorded)
    damage.append(
        f"file identification damaged (bytes 0–{first} before the first intact record);"
        f" read as format version {FORMAT_VERSION}"
    )
    return FORMAT_VERSION, first


def _newer_version_error(path: Path, version: int) -> RecordingError:
    return RecordingError(
        f"{path} was written by a newer groundstation (recording format version {version}; "
        f"this version reads versions 1 to {FORMAT_VERSION}): update groundstation to open it"
    )


def _recorded_format_version(buffer: bytes) -> int | None:
    """``format_version`` from an intact metadata record right after the preamble, if there is one."""
    walk = _Walk(buffer)
    if not walk.is_valid_at(PREAMBLE.size):
        return None
    _, kind, length, _ = RECORD_HEADER.unpack_from(buffer, PREAMBLE.size)
    start = PREAMBLE.size + HEADER_BYTES
    if kind != Kind.METADATA:
        return None
    metadata = _json_object(walk.view[start:start + length], "metadata record", [])
    version = metadata.get("format_version") if metadata else None
    return version if isinstance(version, int) else None


class _Walk:
    """One pass over the records: chunk positions in int64 arrays (the hot path), other records kept aside."""

    def __init__(self, buffer):
        self.buffer = buffer
        self.view = memoryview(buffer)
        self.chunk_t_host_ns, self.chunk_offsets, self.chunk_lengths = array("q"), array("q"), array("q")
        self.others: list[tuple[int, int, int, int]] = []  # (kind, t_host_ns, payload start, payload end)
        self.damage: list[str] = []
        # The intact record starts in [_searched_from, _searched_until), once a resynchronisation
        # searched there: inside it a record is looked up, never checked again (so checking false
        # markers costs no more than one search of the bytes they claim).
        self._searched_from = self._searched_until = 0
        self._intact: set[int] = set()
        self._intact_sorted = np.zeros(0, dtype=np.int64)

    def run_intact(self, position: int) -> int:
        """The intact records from ``position`` on, found with array operations a block of the file at a time:
        the record markers are located, each record's end computed from its header, and the records that
        follow one another from ``position`` with sound lengths and CRCs are taken, as ``run`` takes them
        (``run`` walks one record at a time, ~3 µs each: a second for an hour of chunks). Returns where they
        end: ``run`` goes on from there (damage, a false marker, a resynchronisation, the end). Only from a
        walk's start, before any search."""
        data = np.frombuffer(self.buffer, dtype=np.uint8)
        if self._intact or len(data) - position < RECORD_OVERHEAD_BYTES:
            return position
        for block in range(position - position % INTACT_BLOCK_BYTES, len(data), INTACT_BLOCK_BYTES):
            starts = _marker_positions(data, block, block + INTACT_BLOCK_BYTES)
            starts = starts[starts >= position]  # markers inside the records taken start none
            n, position = self._take_intact(data, starts, position)
            if n < len(starts):
                break  # a record that is not intact, a marker that starts none: ``run`` decides there
        return position

    def _take_intact(self, data: np.ndarray, starts: np.ndarray, position: int) -> tuple[int, int]:
        """Of the records at marker ``starts`` (sorted), those that follow one another from ``position``,
        are sound and pass their CRC, up to the first that does not: taken. Returns (how many, where they end)."""
        size = len(data)
        starts = starts[starts + RECORD_OVERHEAD_BYTES <= size]
        header = np.lib.stride_tricks.sliding_window_view(data, RECORD_HEADER.size)[starts]
        kinds = header[:, MARKER_BYTES].astype(np.int64)
        lengths = header[:, MARKER_BYTES + 1:MARKER_BYTES + 5].copy().view("<u4").reshape(-1).astype(np.int64)
        t_host_ns = header[:, MARKER_BYTES + 5:].copy().view("<i8").reshape(-1)
        ends = starts + HEADER_BYTES + lengths  # each record's payload end, where its CRC is
        follows = starts == np.concatenate(([position], ends[:-1] + CRC.size))
        n = int(np.cumprod(follows & (lengths <= MAX_PAYLOAD_BYTES) & (ends + CRC.size <= size)).sum())
        crcs = np.lib.stride_tricks.sliding_window_view(data, CRC.size)[ends[:n]].copy().view("<u4").reshape(-1)
        view, crc32 = self.view, zlib.crc32
        intact = np.fromiter((crc32(view[a + MARKER_BYTES:b]) for a, b in zip(starts[:n].tolist(), ends[:n].tolist())),
                             dtype=np.uint32, count=n) == crcs
        n = n if intact.all() else int(np.argmin(intact))  # up to the first record whose CRC fails
        chunk = kinds[:n] == Kind.CHUNK.value
        self.chunk_t_host_ns.frombytes(t_host_ns[:n][chunk].astype("<i8").tobytes())
        self.chunk_offsets.frombytes((starts[:n][chunk] + HEADER_BYTES).astype("<i8").tobytes())
        self.chunk_lengths.frombytes(lengths[:n][chunk].astype("<i8").tobytes())
        others = np.flatnonzero(~chunk)
        self.others += zip(kinds[others].tolist(), t_host_ns[others].tolist(), (starts[others] + HEADER_BYTES).tolist(),
                           ends[others].tolist())
        return n, int(ends[n - 1]) + CRC.size if n else position

    def run(self, position: int) -> None:
        buffer, view, size = self.buffer, self.view, len(self.buffer)
        unpack_header, unpack_crc, crc32 = RECORD_HEADER.unpack_from, CRC.unpack_from, zlib.crc32
        append_t, append_offset, append_length = (
            self.chunk_t_host_ns.append, self.chunk_offsets.append, self.chunk_lengths.append,
        )
        chunk = Kind.CHUNK.value
        searched_from, searched_until, intact = self._searched_from, self._searched_until, self._intact
        while position < size:
            if size - position >= RECORD_OVERHEAD_BYTES:
                marker, kind, length, t_host_ns = unpack_header(buffer, position)
                payload = position + HEADER_BYTES
                end = payload + length
                if (
                    position in intact
                    if searched_from <= position < searched_until
                    else marker == MARKER
                    and length <= MAX_PAYLOAD_BYTES
                    and end + CRC.size <= size
                    and crc32(view[position + MARKER_BYTES:end]) == unpack_crc(buffer, end)[0]
                ):
                    if kind == chunk:
                        append_t(t_host_ns)
                        append_offset(payload)
                        append_length(length)
                    else:
                        self.others.append((kind, t_host_ns, payload, end))
                    position = end + CRC.size
                    continue
            position = self._skip_damage(position)
            searched_from, searched_until, intact = self._searched_from, self._searched_until, self._intact

    def drop_repeats(self) -> None:
        """Records that repeat earlier ones (same kind, host time and payload: a byte range written twice)
        are damage, read once and said once. Intact chunks arrive in increasing host time, so only a
        file whose chunk times step back is searched."""
        buffer, view, first_repeat = self.buffer, self.view, []

        def repeats(kind, t_host_ns, start, end, seen: dict) -> bool:
            key = (kind, t_host_ns, end - start, buffer[end:end + CRC.size])
            earlier = seen.setdefault(key, start)
            if earlier != start and view[earlier:earlier + end - start] == view[start:end]:
                first_repeat.append(start - HEADER_BYTES)
                return True
            return False

        t = self.chunk_t_host_ns
        if len(t) > 1 and (np.diff(np.frombuffer(t, dtype=np.int64)) <= 0).any():
            seen: dict = {}
            dropped = [i for i, (t_ns, offset, length) in enumerate(zip(t, self.chunk_offsets, self.chunk_lengths))
                       if repeats(Kind.CHUNK, t_ns, offset, offset + length, seen)]
            # A repeated range is a run of indices: delete run by run, from the end (lists or arrays alike).
            runs = [[i, i + 1] for i in dropped[:1]]
            for i in dropped[1:]:
                if i == runs[-1][1]:
                    runs[-1][1] = i + 1
                else:
                    runs.append([i, i + 1])
            for start, stop in reversed(runs):
                for values in (self.chunk_t_host_ns, self.chunk_offsets, self.chunk_lengths):
                    del values[start:stop]
        seen = {}
        self.others[:] = [record for record in self.others if not repeats(*record, seen)]
        if first_repeat:
            self.damage.append(f"{len(first_repeat)} records repeat earlier ones (same kind, time and bytes; from byte "
                               f"{min(first_repeat)}): read once")

    def is_valid_at(self, position: int) -> bool:
        if len(self.buffer) - position < RECORD_OVERHEAD_BYTES:
            return False
        marker, _, length, _ = RECORD_HEADER.unpack_from(self.buffer, position)
        end = position + HEADER_BYTES + length
        return (
            marker == MARKER
            and length <= MAX_PAYLOAD_BYTES  # bounds the CRC work a false marker can cause
            and end + CRC.size <= len(self.buffer)
            and zlib.crc32(self.view[position + MARKER_BYTES:end]) == CRC.unpack_from(self.buffer, end)[0]
        )

    def next_valid(self, position: int, stop: int | None = None) -> int | None:
        """The first intact record starting in [position, stop), stop the file's end by default."""
        stop = len(self.buffer) if stop is None else min(stop, len(self.buffer))
        while position < stop:
            if not self._searched_from <= position < self._searched_until:
                self._intact_sorted, self._searched_until = search.intact_records(self.buffer, position, stop)
                self._searched_from, self._intact = position, set(self._intact_sorted.tolist())
            after = self._intact_sorted[np.searchsorted(self._intact_sorted, position):]
            if len(after):
                return int(after[0]) if after[0] < stop else None
            position = self._searched_until
        return None

    def _skip_damage(self, position: int) -> int:
        """Describes the damage starting at ``position``; returns where reading resumes."""
        size = len(self.buffer)
        resume = self.next_valid(position + 1)
        stop = size if resume is None else resume
        declared_end = self._declared_end(position)
        if declared_end == stop:
            self.damage.append(
                f"record at byte {position} failed its CRC; skipped ({stop - position} bytes)"
            )
        elif resume is None and (declared_end is None or declared_end > size) and self._starts_record(position):
            self.damage.append(
                f"truncated tail: last {size - position} bytes of an incomplete record ignored"
                " (the recording was cut off)"
            )
        else:
            self.damage.append(f"unreadable bytes {position}–{stop} skipped ({stop - position} bytes)")
        return stop

    def _starts_record(self, position: int) -> bool:
        head = self.buffer[position:position + MARKER_BYTES]
        return MARKER.startswith(head) if len(head) < MARKER_BYTES else head == MARKER

    def _declared_end(self, position: int) -> int | None:
        """Where the record at ``position`` would end by its own length field, if it has one."""
        if not self._starts_record(position) or len(self.buffer) - position < HEADER_BYTES:
            return None
        _, _, length, _ = RECORD_HEADER.unpack_from(self.buffer, position)
        return position + RECORD_OVERHEAD_BYTES + length


def _marker_positions(data: np.ndarray, start: int, stop: int) -> np.ndarray:
    """Where ``MARKER`` starts in ``data[start:stop]``."""
    block = data[start:stop + MARKER_BYTES - 1]
    at = np.flatnonzero(block[: max(len(block) - MARKER_BYTES + 1, 0)] == MARKER[0])
    for i in range(1, MARKER_BYTES):
        at = at[block[at + i] == MARKER[i]]
    return at + start


def _chunk_time_jumps(chunk_t_host_ns) -> list[str]:
    """A finding for steps forward in arrival time that a recording's clock cannot make."""
    times = np.asarray(chunk_t_host_ns, dtype=np.int64)
    # A step forward is exact as uint64 even where int64 subtraction wraps.
    steps_ns = (times[1:] - times[:-1]).view(np.uint64)
    jumps = np.flatnonzero((times[1:] > times[:-1]) & (steps_ns > MAX_CHUNK_STEP_NS))
    if not len(jumps):
        return []
    first = int(jumps[0])
    return [f"chunk arrival time jumps forward by more than a year {len(jumps)} time(s) (first by"
            f" {int(steps_ns[first]) / 1e9:.3g} s after chunk {first}): arrival times after a jump are damaged"]


def _assemble(path: Path, version: int, buffer: bytes, walk: _Walk, damage: list[str]) -> Recording:
    metadata: dict | None = None
    t_open_ns = None
    events: list[tuple[int, dict]] = []
    blocks: list[tuple[memoryview, list[str]]] = []
    closed_cleanly = False
    for kind, t_host_ns, start, end in walk.others:
        payload = walk.view[start:end]
        where = f"at byte {start - HEADER_BYTES}"
        if kind == Kind.METADATA and metadata is None:
            metadata = _json_object(payload, f"metadata record {where}", damage)
            t_open_ns = t_host_ns if metadata is not None else None
        elif kind == Kind.EVENT:
            event = _json_object(payload, f"event record {where}", damage)
            if event is not None:
                events.append((t_host_ns, event))
        elif kind == Kind.SAMPLES:
            _add_block(payload, where, blocks, damage)
        elif kind == Kind.END:
            closed_cleanly = True
        else:
            damage.append(f"record of unknown kind {kind} {where} skipped (written by a newer groundstation?)")
    if metadata is None:
        damage.append("metadata record lost: port, start time and settings of this recording are unknown")
    return Recording(
        path=path,
        version=version,
        metadata=metadata or {},
        t_open_ns=t_open_ns,
        events=events,
        damage=damage,
        closed_cleanly=closed_cleanly,
        record_counts={"chunks": len(walk.chunk_offsets), "events": len(events), "sample_blocks": len(blocks)},
        _buffer=buffer,
        _chunk_t_host_ns=walk.chunk_t_host_ns,
        _chunk_offsets=walk.chunk_offsets,
        _chunk_lengths=walk.chunk_lengths,
        _sample_blocks=[payload for payload, _ in blocks],
    )


def _json_object(payload: memoryview, what: str, damage: list[str]) -> dict | None:
    try:
        value = json.loads(bytes(payload))
    except (ValueError, RecursionError):  # RecursionError: nested deeper than any record we write
        value = None
    if not isinstance(value, dict):
        damage.append(f"{what} is not a JSON object; skipped")
        return None
    return value


def _add_block(payload: memoryview, where: str, blocks: list[tuple[memoryview, list[str]]], damage: list[str]) -> None:
    """A samples record's payload with its column names, once it decodes (its columns are not kept)."""
    try:
        names = list(samples.decode_block(payload))
    except ValueError as error:
        damage.append(f"samples record {where}: {error}; skipped")
        return
    if blocks and names != blocks[0][1]:
        damage.append(f"samples record {where} has other columns than the first block; skipped")
        return
    blocks.append((payload, names))

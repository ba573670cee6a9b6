"""Opening a recording: every intact record is recovered, every loss is described in ``damage``.

The whole file is read into memory and walked record by record with ``struct.unpack_from``; a
record counts only if its marker, length and CRC-32 agree. Where they do not, the reader looks for
the next record that does (resynchronisation) and reports the bytes in between.
"""

from __future__ import annotations

import functools
import itertools
import json
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from groundstation.recording import samples, sniff
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
MARKER_BYTES = len(MARKER)


@dataclass
class Recording:
    """A recording read into memory. Chunks are served in file order (the order they arrived)."""

    path: Path
    version: int
    metadata: dict  # empty if the metadata record was lost (then ``damage`` says so)
    t_open_ns: int | None  # host monotonic clock when the writer opened the file (at metadata['start_utc'])
    events: list[tuple[int, dict]]  # (t_host_ns, event) in file order
    samples: dict[str, np.ndarray]  # imported float64 columns, all blocks joined; empty if none
    damage: list[str]  # human-readable findings; empty for an intact file
    closed_cleanly: bool  # the END record is there: the writer was not killed
    record_counts: dict[str, int]  # intact records: chunks, events, sample_blocks
    _buffer: bytes = field(repr=False)
    _chunk_t_host_ns: list[int] = field(repr=False)
    _chunk_offsets: list[int] = field(repr=False)
    _chunk_lengths: list[int] = field(repr=False)

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

    def stream(self) -> tuple[bytes, np.ndarray, np.ndarray]:
        """Every chunk's bytes joined, each chunk's end offset in them and its arrival time (the batch path)."""
        buffer = np.frombuffer(self._buffer, dtype=np.uint8)
        offsets = np.array(self._chunk_offsets, dtype=np.int64)
        lengths = np.array(self._chunk_lengths, dtype=np.int64)
        # Chunks lie in file order between record headers: keep the bytes inside [offset, offset + length).
        edges = np.zeros(len(buffer) + 1, dtype=np.int8)
        np.add.at(edges, offsets, 1)
        np.add.at(edges, offsets + lengths, -1)
        data = buffer[np.cumsum(edges[:-1], dtype=np.int8).view(bool)].tobytes()
        return data, np.cumsum(lengths), self.chunk_t_host_ns

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
    try:
        buffer = path.read_bytes()
    except FileNotFoundError:
        raise RecordingError(f"{path}: no such file") from None
    except OSError as error:
        raise RecordingError(f"{path}: cannot be read ({error.strerror})") from None
    damage: list[str] = []
    version, start = _read_preamble(path, buffer, damage)
    walk = _Walk(buffer)
    walk.run(start)
    walk.drop_repeats()
    damage += walk.damage
    if not walk.chunk_offsets and not walk.others:
        raise RecordingError(f"{path}: nothing could be read: " + "; ".join(damage))
    return _assemble(path, version, buffer, walk, damage)


def _read_preamble(path: Path, buffer: bytes, damage: list[str]) -> tuple[int, int]:
    """(format version, where the records start); raises for an empty, cut or foreign file."""
    if not buffer:
        raise RecordingError(f"{path} is empty (0 bytes): nothing was recorded")
    if buffer.startswith(MAGIC) or MAGIC.startswith(buffer):
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
    first = _Walk(buffer).next_valid(0)
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
    """One pass over the records: chunk positions in lists (the hot path), other records kept aside."""

    def __init__(self, buffer: bytes):
        self.buffer = buffer
        self.view = memoryview(buffer)
        self.chunk_t_host_ns: list[int] = []
        self.chunk_offsets: list[int] = []
        self.chunk_lengths: list[int] = []
        self.others: list[tuple[int, int, int, int]] = []  # (kind, t_host_ns, payload start, payload end)
        self.damage: list[str] = []

    def run(self, position: int) -> None:
        buffer, view, size = self.buffer, self.view, len(self.buffer)
        unpack_header, unpack_crc, crc32 = RECORD_HEADER.unpack_from, CRC.unpack_from, zlib.crc32
        append_t, append_offset, append_length = (
            self.chunk_t_host_ns.append, self.chunk_offsets.append, self.chunk_lengths.append,
        )
        chunk = Kind.CHUNK.value
        while position < size:
            if size - position >= RECORD_OVERHEAD_BYTES:
                marker, kind, length, t_host_ns = unpack_header(buffer, position)
                payload = position + HEADER_BYTES
                end = payload + length
                if (
                    marker == MARKER
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
        if any(later <= earlier for earlier, later in itertools.pairwise(t)):
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

    def next_valid(self, position: int) -> int | None:
        while (position := self.buffer.find(MARKER, position)) >= 0:
            if self.is_valid_at(position):
                return position
            position += 1
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
        if not self.buffer.startswith(MARKER, position) or len(self.buffer) - position < HEADER_BYTES:
            return None
        _, _, length, _ = RECORD_HEADER.unpack_from(self.buffer, position)
        return position + RECORD_OVERHEAD_BYTES + length


def _assemble(path: Path, version: int, buffer: bytes, walk: _Walk, damage: list[str]) -> Recording:
    metadata: dict | None = None
    t_open_ns = None
    events: list[tuple[int, dict]] = []
    blocks: list[dict[str, np.ndarray]] = []
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
        samples={name: np.concatenate([b[name] for b in blocks]) for name in blocks[0]} if blocks else {},
        damage=damage,
        closed_cleanly=closed_cleanly,
        record_counts={"chunks": len(walk.chunk_offsets), "events": len(events), "sample_blocks": len(blocks)},
        _buffer=buffer,
        _chunk_t_host_ns=walk.chunk_t_host_ns,
        _chunk_offsets=walk.chunk_offsets,
        _chunk_lengths=walk.chunk_lengths,
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


def _add_block(payload: memoryview, where: str, blocks: list[dict[str, np.ndarray]], damage: list[str]) -> None:
    try:
        block = samples.decode_block(payload)
    except ValueError as error:
        damage.append(f"samples record {where}: {error}; skipped")
        return
    if blocks and list(block) != list(blocks[0]):
        damage.append(f"samples record {where} has other columns than the first block; skipped")
        return
    blocks.append(block)

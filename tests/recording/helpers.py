"""Recordings whose record boundaries are known, for the damage tests."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from firmware_protocol import SPEC

from groundstation.cli import main
from groundstation.recording import RecordingWriter
from groundstation.recording.format import RECORD_HEADER, RECORD_OVERHEAD_BYTES, Kind

PREAMBLE_BYTES = 12


@dataclass
class Small:
    data: bytes
    chunks: list[tuple[int, bytes]]
    # (start, end) byte spans: spans[0] is the metadata record, then one per chunk, then the event
    # record, then the END record.
    spans: list[tuple[int, int]]

    def chunk_span(self, index: int) -> tuple[int, int]:
        return self.spans[1 + index]


def write_small(path: Path, n_chunks: int = 6) -> Small:
    chunks = [(1_000_000 * (i + 1), bytes([0xA5, i, 255 - i]) * (i + 1)) for i in range(n_chunks)]
    ends = []
    with RecordingWriter(path, {"port": "t"}) as writer:
        ends.append(writer.bytes_written)
        for t_host_ns, data in chunks:
            writer.write_chunk(t_host_ns, data)
            ends.append(writer.bytes_written)
        writer.write_event(9_000_000, {"note": "end"})
        ends.append(writer.bytes_written)
    data = path.read_bytes()
    ends.append(len(data))
    starts = [PREAMBLE_BYTES] + ends[:-1]
    return Small(data, chunks, list(zip(starts, ends)))


def record_spans(data: bytes) -> list[tuple[int, int, int]]:
    """(kind, start, end) of every record of an intact recording's bytes, in file order."""
    spans, pos = [], PREAMBLE_BYTES
    while pos < len(data):
        _, kind, length, _ = RECORD_HEADER.unpack_from(data, pos)
        end = pos + RECORD_OVERHEAD_BYTES + length
        spans.append((kind, pos, end))
        pos = end
    return spans


def recording_without_config(folder: Path) -> Path:
    """A simulated 8 s hover (±4 g) whose records holding a CONFIG frame fail their CRC: lost, and said to be."""
    assert main(["simulate", "--scenario", "hover", "--duration", "8", "--seed", "4", "--out", str(folder / "whole.gsrec")]) == 0
    data = bytearray((folder / "whole.gsrec").read_bytes())
    config = SPEC.frame("CONFIG")
    header = bytes((SPEC.sync, config.payload_size, config.id))
    spans = [(start, end) for kind, start, end in record_spans(bytes(data)) if kind == Kind.CHUNK and header in data[start:end]]
    assert spans
    for _, end in spans:
        data[end - 1] ^= 0xFF
    path = folder / "without-config.gsrec"
    path.write_bytes(bytes(data))
    return path

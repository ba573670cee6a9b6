"""The intact records found with array operations (``_Walk.run_intact``) are those the record-by-record
walk (``_Walk.run``) takes, on intact files and on files with false markers, damage and a cut end: each
file is walked both ways and the chunk index and other records compared, then the reader's damage."""

import numpy as np
import pytest

from groundstation.recording import reader
from groundstation.recording.format import MARKER, PREAMBLE, Kind, encode_preamble, encode_record


def walked(data: bytes, fast: bool):
    walk = reader._Walk(data)
    start = PREAMBLE.size
    walk.run(walk.run_intact(start) if fast else start)
    return ([np.asarray(a).tolist() for a in (walk.chunk_t_host_ns, walk.chunk_offsets, walk.chunk_lengths)],
            walk.others, walk.damage)


def recording_bytes(chunks: int, seed: int = 3) -> bytes:
    rng = np.random.default_rng(seed)
    records = [encode_record(Kind.METADATA, 0, b'{"source": "test"}')]
    for k in range(chunks):
        records.append(encode_record(Kind.CHUNK, 1000 + k, rng.integers(0, 256, int(rng.integers(1, 200)), dtype=np.uint8).tobytes()))
        if k % 97 == 0:
            records.append(encode_record(Kind.EVENT, 1000 + k, b'{"kind": "note"}'))
    return encode_preamble() + b"".join(records)


CASES = {
    "intact": lambda d: d,
    "a false marker inside a chunk": lambda d: d.replace(d[400:404], MARKER, 1)[:len(d)],
    "a flipped byte in the middle": lambda d: d[:len(d) // 2] + bytes([d[len(d) // 2] ^ 0xFF]) + d[len(d) // 2 + 1:],
    "garbage between records": lambda d: d[:5000] + b"\x00" * 37 + d[5000:],
    "a cut end": lambda d: d[:-7],
}


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("block_bytes", [64, 4096, reader.INTACT_BLOCK_BYTES])
def test_the_intact_records_are_those_the_walk_takes(case, block_bytes, monkeypatch):
    monkeypatch.setattr(reader, "INTACT_BLOCK_BYTES", block_bytes)
    data = CASES[case](recording_bytes(3000))
    assert walked(data, fast=True) == walked(data, fast=False)


def test_a_payload_holding_a_whole_record_does_not_fool_it():
    """A chunk whose bytes are themselves a valid record: the walk never looks inside a record it took."""
    inner = encode_record(Kind.CHUNK, 5, b"inner")
    data = encode_preamble() + encode_record(Kind.METADATA, 0, b"{}") + encode_record(Kind.CHUNK, 7, inner * 3)
    fast, slow = walked(data, fast=True), walked(data, fast=False)
    assert fast == slow and fast[0][2] == [len(inner) * 3]

"""Recording write and read speed: a 1-hour 100 Hz session in the worst case, one chunk per frame.

    python bench/bench_recording.py [--chunks N] [--chunk-bytes B] [--repeats R]

Prints the file size and, as medians of the repeats, the time to write the chunks, to open the
file (parse and check every record) and to iterate over all chunks.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from groundstation.recording import RecordingWriter, open_recording


def write(path: Path, n_chunks: int, chunk_bytes: int) -> float:
    data = bytes(range(256)) * (chunk_bytes // 256 + 1)
    started = time.perf_counter()
    with RecordingWriter(path, {"port": "bench"}) as writer:
        for i in range(n_chunks):
            writer.write_chunk(i * 10_000_000, data[i % 256:i % 256 + chunk_bytes])
    return time.perf_counter() - started


def read(path: Path) -> tuple[float, float]:
    started = time.perf_counter()
    recording = open_recording(path)
    opened = time.perf_counter()
    total = sum(len(data) for _, data in recording.chunks())
    assert not recording.damage and recording.chunk_count > 0 and total > 0
    return opened - started, time.perf_counter() - opened


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chunks", type=int, default=360_000 * 3, help="default: 1 h at 100 Hz, 3 frames a sample")
    parser.add_argument("--chunk-bytes", type=int, default=24)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        writes, opens, iterations = [], [], []
        for repeat in range(args.repeats):
            path = Path(folder) / f"bench{repeat}.gsrec"
            writes.append(write(path, args.chunks, args.chunk_bytes))
            open_s, iterate_s = read(path)
            opens.append(open_s)
            iterations.append(iterate_s)
            size_mb = os.path.getsize(path) / 1e6
            path.unlink()
    n = args.chunks
    print(f"{n} chunks of {args.chunk_bytes} bytes, file {size_mb:.1f} MB")
    for label, times in (("write", writes), ("open", opens), ("iterate", iterations)):
        median = statistics.median(times)
        print(f"  {label:8s} {median:6.2f} s  ({n / median / 1e6:.2f} M chunks/s)")


if __name__ == "__main__":
    main()

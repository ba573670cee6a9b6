"""Decoder throughput (frames/s) by chunk size, and the false-accept rate on random bytes.

    python bench/bench_decoder.py [--frames N] [--random-mb MB]

Prints medians of several repeats. The baseline measured in the same run is a bare loop that
only finds sync bytes and checks the CRC (no unpacking, no counters): the ratio shows what the
decoder's bookkeeping costs on this machine, whatever else the machine is doing.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from binascii import crc_hqx

from firmware_protocol import SPEC, StreamDecoder, encode, make_frame


def telemetry_stream(n_frames: int, lose_every: int = 0) -> bytes:
    """A realistic mix: IMU_RAW and ATTITUDE at the output rate, STATUS now and then; without every
    ``lose_every``-th frame if given (each gap then takes the decoder's closer look at device time)."""
    imu = SPEC.frame("IMU_RAW")
    att = SPEC.frame("ATTITUDE")
    out = bytearray()
    for i in range(n_frames):
        if lose_every and i % lose_every == lose_every - 1:
            continue
        t_us = i * 10_000
        if i % 100 == 99:
            frame = make_frame("STATUS", i & 0xFF, t_us=t_us, battery=11_800, retransmits=3, lost_acks=0, cpu_load=70, flags=0)
        elif i % 2:
            frame = make_frame("ATTITUDE", i & 0xFF, **dict(zip(att.field_names, (t_us, 16384, 10, -20, 30, 1500, 0))))
        else:
            frame = make_frame("IMU_RAW", i & 0xFF, **dict(zip(imu.field_names, (t_us, 12, -40, 16390, 5, -3, 2, 2512))))
        out += encode(frame)
    return bytes(out)


def decode_all(data: bytes, chunk: int) -> int:
    decoder = StreamDecoder()
    count = 0
    for i in range(0, len(data), chunk):
        count += len(decoder.feed(data[i : i + chunk]))
    return count


def bare_crc_scan(data: bytes, chunk: int) -> int:
    """Baseline: find sync, check CRC, nothing else (whole buffer, no chunk bookkeeping)."""
    count = pos = 0
    find = data.find
    while (start := find(0xA5, pos)) >= 0 and start + 4 <= len(data):
        end = start + 6 + data[start + 1]
        if not crc_hqx(data[start + 1 : end], 0xFFFF):
            count += 1
            pos = end
        else:
            pos = start + 1
    return count


def median_rate(function, data: bytes, chunk: int, repeats: int) -> tuple[float, int]:
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        count = function(data, chunk)
        rates.append(count / (time.perf_counter() - t0))
    return statistics.median(rates), count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--random-mb", type=float, default=16)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    data = telemetry_stream(args.frames)
    print(f"stream: {args.frames} frames, {len(data) / args.frames:.1f} bytes/frame on average")
    base, _ = median_rate(bare_crc_scan, data, len(data), args.repeats)
    print(f"baseline (bare sync+CRC scan):       {base / 1e6:6.2f} M frames/s")
    for chunk in (4096, 32):
        rate, count = median_rate(decode_all, data, chunk, args.repeats)
        assert count == args.frames
        print(f"StreamDecoder, {chunk:5d}-byte chunks:   {rate / 1e6:6.2f} M frames/s  ({rate / base:.2f} x baseline)")
    lossy = telemetry_stream(args.frames, lose_every=20)
    rate, _ = median_rate(decode_all, lossy, 4096, args.repeats)
    print(f"StreamDecoder, 4096-byte chunks, 5 % of frames lost: {rate / 1e6:6.2f} M frames/s  ({rate / base:.2f} x baseline)")

    n_bytes = int(args.random_mb * 1e6)
    decoder = StreamDecoder()
    accepted = 0
    random_bytes = os.urandom(n_bytes)
    for i in range(0, n_bytes, 4096):
        accepted += len(decoder.feed(random_bytes[i : i + 4096]))
    s = decoder.stats
    print(
        f"random bytes: {n_bytes / 1e6:.0f} MB -> {accepted} frames accepted "
        f"({accepted / (n_bytes / 1e6):.3f} per MB), {s.unknown_types} unknown-type frames passed CRC, "
        f"{s.crc_errors} CRC failures, {s.bad_lengths} bad lengths"
    )


if __name__ == "__main__":
    main()

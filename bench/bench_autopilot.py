"""Autopilot logs and MAVLink decoding: per shared flight log, its duration, IMU rate, import time and
each host estimator's pitch/roll RMS difference from the onboard estimate; then MAVLink decode
throughput (messages/s) of ``MavlinkDecoder`` against pymavlink's own parse loop on the same bytes.

    python bench/bench_autopilot.py [--repeats N] [--logs DIR]

Import time is ``load_log`` with the default estimator (``ahf``): reading, mapping, running it, aligning
the onboard estimate. Agreement is with every estimator but the GPS-aided ``ukf``/``sssrukf``. The decode
baseline is ``MAVLink.parse_buffer`` (pymavlink's parser alone, no mapping) on the packets of
``ardurover_boat_sitl_autotest.tlog`` (its timestamps stripped), in 4 KB chunks, measured in the same run.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.autopilot.agreement import onboard_agreement
from groundstation.autopilot.decoder import MavlinkDecoder
from groundstation.session_makers.flight_log_session import load_log
from groundstation.autopilot.tlog import packets
from groundstation.estimation import runnable
from groundstation.formats import FILE_AIDING

LOGS = Path(__file__).resolve().parents[1] / ".." / "shared" / "datasets" / "flightlogs"
CHUNK = 4096


def log_figures(path: Path, repeats: int) -> str:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        data = load_log(path)
        times.append(time.perf_counter() - start)
    meta = data.metadata
    head = f"| {path.name} | {data.time_s[-1]:.1f} | {meta.get('imu_rate_hz', float('nan')):.1f} | {statistics.median(times):.2f} |"
    if not data.estimated:
        return head + " no IMU logged: onboard attitude only |"
    names = runnable(FILE_AIDING)
    full = load_log(path, names)
    figures = onboard_agreement(full)
    cells = ", ".join(f"{n} {f['pitch_rms_deg']:.2f}/{f['roll_rms_deg']:.2f}" for n, f in figures.items())
    slow = " (IMU too slow for host filtering)" if "imu_warning" in meta else ""
    return head + f" {cells}{slow} |"


def pymavlink_parse(data: bytes) -> int:
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    count = 0
    for i in range(0, len(data), CHUNK):
        count += sum(1 for m in parser.parse_buffer(data[i : i + CHUNK]) or () if m.get_type() != "BAD_DATA")
    return count


def ours(data: bytes) -> int:
    decoder = MavlinkDecoder()
    for i in range(0, len(data), CHUNK):
        decoder.feed(data[i : i + CHUNK])
    return decoder.stats.messages


def rate(function, data: bytes, repeats: int) -> tuple[float, int]:
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        count = function(data)
        runs.append(time.perf_counter() - start)
    return count / statistics.median(runs), count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--logs", type=Path, default=LOGS)
    args = parser.parse_args()
    print("| file | duration (s) | IMU rate (Hz) | import time (s, median) | pitch/roll RMS difference from onboard (deg) |")
    print("|---|---|---|---|---|")
    for path in sorted(args.logs.glob("*")):
        if path.suffix.lower() in (".tlog", ".bin", ".ulg"):
            print(log_figures(path, args.repeats), flush=True)
    raw = b"".join(p for _, p in packets((args.logs / "ardurover_boat_sitl_autotest.tlog").read_bytes()) if p is not None)
    base, n_base = rate(pymavlink_parse, raw, args.repeats)
    mine, n_mine = rate(ours, raw, args.repeats)
    assert n_base == n_mine, (n_base, n_mine)
    print(f"\nMAVLink decode, {n_mine} messages ({len(raw) / n_mine:.1f} bytes each), {CHUNK}-byte chunks, median of {args.repeats}:")
    print(f"pymavlink parse_buffer (baseline):     {base / 1e3:8.1f} k messages/s")
    print(f"MavlinkDecoder.feed (parse + mapping): {mine / 1e3:8.1f} k messages/s  ({mine / base:.2f} x baseline)")


if __name__ == "__main__":
    main()

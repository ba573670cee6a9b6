"""Session figures: headless replay of a 1-hour 100 Hz recording to CSV, and the live pipeline.

    python bench/bench_session.py [--hours H] [--live-seconds S]

1. Replay: a simulated 1-hour flight (mode raw, 100 Hz) is written as a recording; then, each in a
   fresh process (so peak memory is that step's own): decoding only (the baseline), and the full
   job: open, replay through ahf + hf + ecf, export CSV. Prints seconds, x real time and peak RSS.
2. Live: the simulated bridge on a pseudo-terminal, read by a LiveSession for S seconds: CPU % of
   this process (reader thread + pipeline + recorder) and the latency from a chunk's arrival stamp
   to its estimates being in the tables (p50/p99).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

JOB = r"""
import json, resource, sys, time
from groundstation.recording import open_recording
t0 = time.perf_counter()
recording = open_recording(sys.argv[1])
if sys.argv[2] == "decode":
    from firmware_protocol import StreamDecoder
    decoder = StreamDecoder()
    for t, data in recording.chunks():
        decoder.feed(data)
    rows = decoder.stats.frames
    t_replay = time.perf_counter() - t0
else:
    from groundstation.export.columns import export_columns
    from groundstation.export.tabular import write_csv
    from groundstation.session_makers.load import from_pipeline
    from groundstation.session_makers.replay import replay
    pipeline = replay(recording, filters=("ahf", "hf", "ecf"))
    t_replay = time.perf_counter() - t0
    columns = export_columns(from_pipeline(recording, pipeline))
    write_csv(columns, sys.argv[3], overwrite=True)
    rows = len(columns["time_s"])
seconds = time.perf_counter() - t0
print(json.dumps({"seconds": seconds, "replay_seconds": t_replay, "rows": rows, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def make_recording(path: Path, hours: float) -> float:
    from groundstation.recording import RecordingWriter
    from groundstation.sim.firmware import FirmwareSettings
    from groundstation.sim.stream import Scenario, SimStream

    duration_s = hours * 3600
    stream = SimStream(Scenario(profile="flight", duration_s=duration_s, firmware=FirmwareSettings(mode="raw")))
    with RecordingWriter(path, {"source": "bench", "filters": ["ahf"]}) as writer:
        t = 0.0
        while t < duration_s:
            t += 60.0
            for chunk in stream.advance(t):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
        for chunk in stream.flush():
            writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)
    return duration_s


def run_job(recording: Path, kind: str, out: Path) -> dict:
    result = subprocess.run([sys.executable, "-c", JOB, str(recording), kind, str(out)], capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def bench_replay(hours: float, repeats: int) -> None:
    with tempfile.TemporaryDirectory() as folder:
        recording, out = Path(folder) / "hour.gsrec", Path(folder) / "hour.csv"
        t0 = time.perf_counter()
        duration_s = make_recording(recording, hours)
        print(f"simulated {duration_s / 3600:g} h recording ({recording.stat().st_size / 1e6:.0f} MB) in {time.perf_counter() - t0:.0f} s")
        base_s = 0.0
        for kind in ("decode", "full"):
            runs = [run_job(recording, kind, out) for _ in range(repeats)]
            seconds = float(np.median([r["seconds"] for r in runs]))
            label = "decode only (baseline)" if kind == "decode" else "replay ahf+hf+ecf -> CSV"
            replay_s = float(np.median([r["replay_seconds"] for r in runs]))
            print(f"{label:<26} {seconds:6.1f} s median of {repeats}  {duration_s / seconds:6.0f}x real time  "
                  f"peak RSS {max(r['peak_mb'] for r in runs):5.0f} MB  (decoding/replay {replay_s:.1f} s"
                  + (f", {seconds / base_s:.1f}x the baseline)" if base_s else ")"))
            base_s = base_s or seconds
        print(f"CSV: {out.stat().st_size / 1e6:.0f} MB, {runs[0]['rows']} rows")


def bench_live(seconds: float) -> None:
    from groundstation.session_makers.live import LiveSession
    from groundstation.session_makers.pipeline import Pipeline
    from groundstation.sources import SerialSource

    bridge = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "flight", "--mode", "both"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        pty = bridge.stdout.readline().split()[-1]
        with tempfile.TemporaryDirectory() as folder:
            session = LiveSession(SerialSource(pty), Pipeline(("ahf", "hf", "ecf")), recordings_dir=folder)
            latencies_ns: list[int] = []
            feed = session.pipeline.feed

            def timed_feed(t_host_ns, data):
                n = feed(t_host_ns, data)
                if n:
                    latencies_ns.append(time.monotonic_ns() - t_host_ns)
                return n

            session.pipeline.feed = timed_feed
            with session:
                time.sleep(1.5)  # past the bridge's boot second
                cpu0, wall0, rows0 = time.process_time(), time.monotonic(), len(session.pipeline.imu)
                latencies_ns.clear()
                time.sleep(seconds)
                cpu, wall, rows = time.process_time() - cpu0, time.monotonic() - wall0, len(session.pipeline.imu) - rows0
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)
    p50, p99 = np.percentile(np.array(latencies_ns) / 1e6, [50, 99])
    print(f"live through the pty: {rows / wall:.1f} samples/s, CPU {100 * cpu / wall:.1f} % of one core "
          f"(reader + decoder + ahf/hf/ecf + recorder), arrival -> estimate latency p50 {p50:.3f} ms, p99 {p99:.3f} ms "
          f"({len(latencies_ns)} chunks)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=1.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--live-seconds", type=float, default=20.0)
    args = parser.parse_args()
    bench_replay(args.hours, args.repeats)
    bench_live(args.live_seconds)


if __name__ == "__main__":
    main()

"""An hour of the app's own flight: opening it, exporting it, and the memory that takes against its length.

    python bench/bench_export_memory.py [--minutes 10,60,240] [--live-minutes 60]

Each length is simulated once (``groundstation simulate --scenario flight``). Every case runs in a fresh
process that first runs it on a 20 s recording (so that what it imports on first use is imported: numpy,
numba and the estimators' compiled kernels from numba's cache, pyarrow, the loaders) and then resets the
kernel's peak-RSS mark (/proc/self/clear_refs, Linux):
"beyond the libraries" is the case's peak RSS minus the RSS after those imports; CPU is the case's
process time, imports excluded. The cases, all in the same run:

- ``decode``: the baseline, the recording read and its link decoded (``decode_batch``), nothing computed;
- ``bare``: the baseline of an export, that decode and a bare ``pyarrow.parquet.write_table`` of the
  decoded IMU frames (raw columns as float64);
- ``open``: ``load_session`` as File > Open computes it, the estimators run whole (their columns held);
- ``export``: ``groundstation export X.parquet`` as the command runs it (``run_export``: the estimators
  streamed a stretch at a time beside the writer).

``open`` and ``export`` run with the three filters of the issue's table (ahf,hf,ecf) at every length and
with the app's live set of ten at ``--live-minutes``. MB per hour is the slope of the export's peak
between the shortest and the longest length.

``--whole-process`` measures the commands as a user runs them instead, the issue's table: each under
``/usr/bin/time -v`` (CPU seconds user + system, peak RSS, libraries included), with the live set, on
flights with the demo's sensors (``simulate --scenario flight --sensors mag,baro,gps``) of ``--minutes``
and of 20 s: ``export X.parquet``, ``replay`` (the open), ``export X.xlsx``; each run ``--repeats`` times,
the checkouts of ``--tree`` (default: this one; e.g. a baseline's beside it) interleaved; minimum and median.
"""

from __future__ import annotations

import argparse
import gc
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
THREE = "ahf,hf,ecf"


def memory_kb(field: str) -> int:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith(field))


def child(case: str, recording: str, out: str, filters: str, warm_up: str) -> None:
    """One case in this process, after the same case on the short recording ``warm_up`` (every module it
    imports on first use imported, every kernel loaded); prints "baseline_kb peak_kb cpu_s"."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq

    from firmware_protocol.batch import decode_batch
    from groundstation.estimation import create
    from groundstation.export.request import export_request, run_export
    from groundstation.recording import open_recording
    from groundstation.session_makers.load import load_session

    def run(path: str) -> None:
        if case in ("decode", "bare"):
            decoded = decode_batch(*open_recording(path).stream())
            if case == "bare":
                imu = decoded.frames["IMU_RAW"].raw
                pq.write_table(pa.table({f: np.asarray(imu[f], dtype=float) for f in imu.dtype.names}), out)
        elif case == "open":
            load_session(path, filters.split(","))
        else:
            run_export(export_request(path, out, filters=filters.split(","), overwrite=True), load_session)

    for name in filters.split(","):
        create(name)
    run(warm_up)
    gc.collect()
    with open("/proc/self/clear_refs", "w") as clear:
        clear.write("5")  # the peak-RSS mark from here
    baseline = memory_kb("VmRSS")
    cpu_started = time.process_time()
    run(recording)
    print(baseline, memory_kb("VmHWM"), time.process_time() - cpu_started)


def measure(case: str, recording: Path, folder: str, filters: str) -> tuple[float, float, float]:
    out = Path(folder) / "out.parquet"
    warm_up = Path(folder) / "warm-up.gsrec"
    result = subprocess.run([sys.executable, __file__, "--child", case, str(recording), str(out), filters, str(warm_up)], check=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True)
    out.unlink(missing_ok=True)
    baseline_kb, peak_kb, cpu_s = result.stdout.split()
    return int(baseline_kb) / 1024, (int(peak_kb) - int(baseline_kb)) / 1024, float(cpu_s)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", default="10,60,240", help="session lengths in minutes (default 10,60,240)")
    parser.add_argument("--live-minutes", type=float, default=60.0, help="the length opened with the live set too")
    parser.add_argument("--child", nargs=5, help=argparse.SUPPRESS)
    parser.add_argument("--whole-process", action="store_true", help="the commands under /usr/bin/time -v (above)")
    parser.add_argument("--tree", type=Path, action="append", help="with --whole-process: a checkout to run from")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cases", default="parquet,replay,xlsx", help="with --whole-process: which commands")
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    if args.whole_process:
        whole_process([float(m) for m in args.minutes.split(",")], [t.resolve() for t in args.tree or [ROOT]],
                      args.repeats, args.cases.split(","))
        return
    from groundstation.estimation import live_estimators

    live = ",".join(live_estimators())
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    rows = []
    print(f"python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.1f} at the start\n")
    with tempfile.TemporaryDirectory(prefix="bench_export_memory.") as folder:
        subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--scenario", "flight", "--duration", "20",
                        "--out", str(Path(folder) / "warm-up.gsrec")], check=True, env=env, capture_output=True)
        for minutes in [float(m) for m in args.minutes.split(",")]:
            recording = Path(folder) / f"{minutes:g}min.gsrec"
            subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--scenario", "flight", "--duration",
                            str(60 * minutes), "--out", str(recording)], check=True, env=env, capture_output=True)
            cases = [("decode", THREE), ("bare", THREE), ("open", THREE), ("export", THREE)]
            if minutes == args.live_minutes:
                cases += [("open", live), ("export", live)]
            for case, filters in cases:
                rows.append((minutes, case, "live set" if filters == live else filters, *measure(case, recording, folder, filters)))
                print("| {:g} min | {} | {} | {:.0f} | {:.0f} | {:.1f} |".format(*rows[-1]), flush=True)
            recording.unlink()
    print("\n| session | case | filters | RSS after imports (MB) | peak beyond the libraries (MB) | CPU s |\n|---|---|---|---:|---:|---:|")
    for row in rows:
        print("| {:g} min | {} | {} | {:.0f} | {:.0f} | {:.1f} |".format(*row))
    exports = [(m, beyond) for m, case, filters, _, beyond, _ in rows if case == "export" and filters == THREE]
    if len(exports) > 1:
        (m0, b0), (m1, b1) = exports[0], exports[-1]
        print(f"\nexport ({THREE}): MB per hour of session (slope {m0:g} -> {m1:g} min): {(b1 - b0) / ((m1 - m0) / 60):.0f}")
        for (ma, ba), (mb, bb) in zip(exports, exports[1:]):
            print(f"  {ma:g} -> {mb:g} min: {(bb - ba) / ((mb - ma) / 60):.0f} MB per hour")


def timed(command: list[str], tree: Path) -> tuple[float, float]:
    """CPU seconds (user + system) and peak RSS (MB) of ``command`` run from ``tree`` (/usr/bin/time -v)."""
    out = subprocess.run(["/usr/bin/time", "-v", *command], cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)},
                         capture_output=True, text=True)
    if out.returncode:
        sys.exit(f"{' '.join(command)} in {tree} failed:\n{out.stderr[-2000:]}")
    field = {line.split(":")[0].strip(): line.rsplit(":", 1)[1].strip() for line in out.stderr.splitlines() if ":" in line}
    return float(field["User time (seconds)"]) + float(field["System time (seconds)"]), int(field["Maximum resident set size (kbytes)"]) / 1024


def whole_process(minutes: list[float], trees: list[Path], repeats: int, cases: list[str]) -> None:
    import statistics

    from groundstation.estimation import live_estimators

    live = ",".join(live_estimators())
    print(f"python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.1f} at the start; trees: {', '.join(map(str, trees))}\n")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_export_memory.") as folder:
        for length_s in [20.0, *(60 * m for m in minutes)]:
            recording = Path(folder) / f"{length_s:g}s.gsrec"
            subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--scenario", "flight", "--sensors", "mag,baro,gps",
                            "--duration", str(length_s), "--out", str(recording)], check=True, capture_output=True,
                           env={**os.environ, "PYTHONPATH": str(ROOT)})
            commands = {"parquet": ["export", str(recording), "--filters", live, "--out", f"{folder}/out.parquet", "--overwrite"],
                        "xlsx": ["export", str(recording), "--filters", live, "--out", f"{folder}/out.xlsx", "--overwrite"],
                        "replay": ["replay", str(recording), "--filters", live]}
            for case in cases:
                runs: dict[Path, list] = {tree: [] for tree in trees}
                for _ in range(repeats):
                    for tree in trees:
                        runs[tree].append(timed([sys.executable, "-m", "groundstation", *commands[case]], tree))
                for tree, measured in runs.items():
                    cpu, rss = [c for c, _ in measured], [r for _, r in measured]
                    rows.append((f"{length_s / 60:g} min", case, tree.name, min(cpu), statistics.median(cpu), min(rss), statistics.median(rss)))
                    print("| {} | {} | {} | {:.2f} | {:.2f} | {:.0f} | {:.0f} |".format(*rows[-1]), flush=True)
            recording.unlink()
    print("\n| session | command (live set) | tree | CPU s min | CPU s median | peak RSS MB min | peak RSS MB median |\n|---|---|---|---:|---:|---:|---:|")
    for row in rows:
        print("| {} | {} | {} | {:.2f} | {:.2f} | {:.0f} | {:.0f} |".format(*row))


if __name__ == "__main__":
    main()

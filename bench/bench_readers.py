"""Peak memory against file size for the file readers (issue 22: bounded memory and time for any file).

    python bench/bench_readers.py [--sizes-mb 4 16 64] [--repeats 3]

Each reading runs in a fresh process, twice: once for its CPU time and the growth of the peak
resident set over the resident set after imports (VmHWM, reset through /proc/self/clear_refs;
mapped file pages count), once under tracemalloc for the peak of allocations and with zlib.crc32
counting the bytes it hashes. Medians of the repeats. The baseline beside each file is reading it whole
(``Path.read_bytes``): what the recording reader did before. Crafted files: false record markers
(CRC bytes hashed against the file size) and a sparse 2 GiB file of zeros. Flight logs: the
``.tlog``/``.bin``/``.ulg`` readers on /work/shared/datasets/flightlogs, and opening each as a session
(``open``: ``load_session``, what File > Open does; ``open-noest``: the same without estimators, so without
the host estimators' columns) beside pymavlink's own parse of a ``.tlog``
(``pymavlink``: ``mavutil`` + ``recv_match()`` to the end); these two are run once before they are measured
(modules imported on first use, compiled kernels loaded), and their CPU is the median of the repeats
interleaved. ``--flightlogs-only`` measures only the flight logs; ``--tree PATH`` (repeatable) runs every
row from each checkout in turn, interleaved (e.g. a baseline's checkout beside this one).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.crafted_files import false_markers, link_recording, sparse_zeros  # noqa: E402

FLIGHT_LOGS = Path("/work/shared/datasets/flightlogs")
READERS = {
    "whole": "lambda path: Path(path).read_bytes()",
    "recording": "lambda path: open_recording(path)",
    "recording+stream": "lambda path: open_recording(path).stream()",
    "flightlog": "lambda path: read_log(path)",
    "open": "lambda path: load_session(path)",
    "open-noest": "lambda path: load_session(path, ())",
    "pymavlink": "parse_all",
}
WARMED = ("open", "open-noest", "pymavlink")  # run once first: what they import and compile on first use is not the reading

MEASURE = """
import json, sys, time, tracemalloc, zlib
from pathlib import Path
from groundstation.recording import open_recording
from groundstation.recording.format import RecordingError
from groundstation.session_makers.flight_log_session import read_log
from groundstation.session_makers.load import load_session
def parse_all(path):
    from pymavlink import mavutil
    connection = mavutil.mavlink_connection(str(path))
    while connection.recv_match() is not None:
        pass
def hwm_kib():
    status = Path("/proc/self/status").read_text()
    return int(status.split("VmHWM:")[1].split()[0]), int(status.split("VmRSS:")[1].split()[0])
def run():
    try:
        read(sys.argv[1])
        return "read"
    except RecordingError as error:
        return str(error).split(": ", 1)[-1][:60]
read = {reader}
if {warm}:
    run()
Path("/proc/self/clear_refs").write_text("5")  # the peak resident set starts again from now
_, before = hwm_kib()
cpu = time.process_time()
outcome = run()
cpu = time.process_time() - cpu
rss = hwm_kib()[0] - before
hashed = [0]
crc32 = zlib.crc32
def counting(data, value=0):
    hashed[0] += memoryview(data).nbytes
    return crc32(data, value)
zlib.crc32 = counting
tracemalloc.start()
run()
peak = tracemalloc.get_traced_memory()[1]
print(json.dumps({{"peak": peak, "rss_kib": rss, "hashed": hashed[0], "cpu_s": cpu, "outcome": outcome}}))
"""


def measure(reader: str, path: Path, repeats: int, trees: list[Path]) -> dict[Path, dict]:
    """Each tree's medians of ``repeats`` runs, the trees' runs interleaved."""
    runs: dict[Path, list] = {tree: [] for tree in trees}
    code = MEASURE.format(reader=READERS[reader], warm=reader in WARMED)
    for _ in range(repeats):
        for tree in trees:
            out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, cwd=tree,
                                 env={**os.environ, "PYTHONPATH": str(tree)})
            if out.returncode:
                sys.exit(f"measuring {reader} on {path.name} in {tree} failed:\n{out.stderr}")
            runs[tree].append(json.loads(out.stdout))
    return {tree: {key: statistics.median(r[key] for r in rs) if key != "outcome" else rs[0][key] for key in rs[0]}
            for tree, rs in runs.items()}


def row(name: str, reader: str, path: Path, repeats: int, trees: list[Path]) -> str:
    size = path.stat().st_size
    mib = 2**20
    lines = []
    for tree, m in measure(reader, path, repeats, trees).items():
        label = reader if len(trees) == 1 else f"{reader} ({tree.name})"
        lines.append(f"| {name} | {label} | {size / mib:.1f} | {m['peak'] / mib:.1f} | {m['peak'] / size:.2f} |"
                     f" {m['rss_kib'] / 1024:.1f} | {m['hashed'] / size:.2f} | {m['cpu_s']:.2f} | {m['outcome']} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes-mb", type=float, nargs="+", default=[4, 16, 64])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--flightlogs-only", action="store_true")
    parser.add_argument("--suffixes", default=".tlog,.bin,.ulg", help="the flight logs measured, by suffix")
    parser.add_argument("--logs", default="*.*", help="the flight logs measured, by a pattern of their names")
    parser.add_argument("--readers", default="whole,flightlog,open,pymavlink", help="the readers of flight logs")
    parser.add_argument("--tree", type=Path, action="append", help="a checkout to run the rows from (default: this one)")
    args = parser.parse_args()
    trees = [tree.resolve() for tree in args.tree] if args.tree else [ROOT]
    measure_row = lambda name, reader, path: row(name, reader, path, args.repeats, trees)  # noqa: E731
    print("| file | reader | size (MiB) | peak alloc (MiB) | alloc / size | peak RSS growth (MiB) |"
          " CRC bytes / size | CPU (s) | outcome |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for size_mb in [] if args.flightlogs_only else args.sizes_mb:
            path = link_recording(folder / f"link{size_mb:g}.gsrec", size_mb)
            for reader in ("whole", "recording", "recording+stream"):
                print(measure_row(f"recording, {size_mb:g} MiB of link bytes", reader, path), flush=True)
        for false_mb in () if args.flightlogs_only else (2, 8):
            path = false_markers(folder, f"false{false_mb}", false_bytes=false_mb * 2**20, claimed_bytes=2**20)
            print(measure_row(f"{false_mb} MiB of false markers claiming 1 MiB", "recording", path), flush=True)
        if not args.flightlogs_only:
            path = sparse_zeros(folder, "zeros")
            print(measure_row("2 GiB of zeros (sparse)", "recording", path), flush=True)
        for log in sorted(FLIGHT_LOGS.glob(args.logs)):
            if log.suffix in args.suffixes.split(","):
                for reader in args.readers.split(","):
                    if reader != "pymavlink" or log.suffix == ".tlog":  # pymavlink's parse: the .tlog's baseline
                        print(measure_row(log.name, reader, log), flush=True)


if __name__ == "__main__":
    main()

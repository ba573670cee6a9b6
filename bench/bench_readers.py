"""Peak memory against file size for the file readers (issue 22: bounded memory and time for any file).

    python bench/bench_readers.py [--sizes-mb 4 16 64] [--repeats 3]

Each reading runs in a fresh process, twice: once for its CPU time and the growth of the peak
resident set over the resident set after imports (VmHWM, reset through /proc/self/clear_refs;
mapped file pages count), once under tracemalloc for the peak of allocations and with zlib.crc32
counting the bytes it hashes. Medians of the repeats. The baseline beside each file is reading it whole
(``Path.read_bytes``): what the recording reader did before. Crafted files: false record markers
(CRC bytes hashed against the file size) and a sparse 2 GiB file of zeros. Flight logs: the
``.tlog``/``.bin``/``.ulg`` readers on /work/shared/datasets/flightlogs.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.crafted_files import false_markers, link_recording, sparse_zeros  # noqa: E402

FLIGHT_LOGS = Path("/work/shared/datasets/flightlogs")
READERS = {
    "whole": "lambda path: Path(path).read_bytes()",
    "recording": "lambda path: open_recording(path)",
    "recording+stream": "lambda path: open_recording(path).stream()",
    "flightlog": "lambda path: read_log(path)",
}

MEASURE = """
import json, sys, time, tracemalloc, zlib
from pathlib import Path
from groundstation.recording import open_recording
from groundstation.recording.format import RecordingError
from groundstation.autopilot.session import read_log
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


def measure(reader: str, path: Path, repeats: int) -> dict:
    runs = []
    for _ in range(repeats):
        code = MEASURE.format(reader=READERS[reader])
        out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True)
        if out.returncode:
            sys.exit(f"measuring {reader} on {path.name} failed:\n{out.stderr}")
        runs.append(json.loads(out.stdout))
    return {key: statistics.median(r[key] for r in runs) if key != "outcome" else runs[0][key] for key in runs[0]}


def row(name: str, reader: str, path: Path, repeats: int) -> str:
    size = path.stat().st_size
    m = measure(reader, path, repeats)
    mib = 2**20
    return (f"| {name} | {reader} | {size / mib:.1f} | {m['peak'] / mib:.1f} | {m['peak'] / size:.2f} |"
            f" {m['rss_kib'] / 1024:.1f} | {m['hashed'] / size:.2f} | {m['cpu_s']:.2f} | {m['outcome']} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes-mb", type=float, nargs="+", default=[4, 16, 64])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print("| file | reader | size (MiB) | peak alloc (MiB) | alloc / size | peak RSS growth (MiB) |"
          " CRC bytes / size | CPU (s) | outcome |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for size_mb in args.sizes_mb:
            path = link_recording(folder / f"link{size_mb:g}.gsrec", size_mb)
            for reader in ("whole", "recording", "recording+stream"):
                print(row(f"recording, {size_mb:g} MiB of link bytes", reader, path, args.repeats), flush=True)
        for false_mb in (2, 8):
            path = false_markers(folder, f"false{false_mb}", false_bytes=false_mb * 2**20, claimed_bytes=2**20)
            print(row(f"{false_mb} MiB of false markers claiming 1 MiB", "recording", path, args.repeats), flush=True)
        path = sparse_zeros(folder, "zeros")
        print(row("2 GiB of zeros (sparse)", "recording", path, args.repeats), flush=True)
        for log in sorted(FLIGHT_LOGS.glob("*.*")):
            if log.suffix in (".tlog", ".bin", ".ulg"):
                for reader in ("whole", "flightlog"):
                    print(row(log.name, reader, log, args.repeats), flush=True)


if __name__ == "__main__":
    main()

"""Memory of a whole export (``load_session`` -> product -> Parquet) against the session's length.

    python bench/bench_export_memory.py [--minutes 10,60] [--filters ahf,hf,ecf] [--out parquet]

Each length is simulated once (``groundstation simulate --scenario flight``), then exported in a
fresh process that first imports everything the export uses (numpy, numba and the estimators' compiled
kernels, pyarrow, the loaders) and resets the kernel's peak-RSS mark (/proc/self/clear_refs, Linux):
"beyond the libraries" is the export's peak RSS minus the RSS after those imports. MB per hour is the
slope between the shortest and the longest length.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def memory_kb(field: str) -> int:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith(field))


def child(recording: str, out: str, filters: str) -> None:
    """One export in this process; prints "baseline_kb peak_kb cpu_s"."""
    from groundstation.estimation import create
    from groundstation.export.request import export_request, run_export
    from groundstation.session.load import load_session

    for name in filters.split(","):
        create(name)  # the compiled kernels are loaded (from numba's cache) before the baseline
    import pyarrow.csv  # noqa: F401  the writers' libraries, imported before the baseline too
    import pyarrow.parquet  # noqa: F401

    with open("/proc/self/clear_refs", "w") as clear:
        clear.write("5")  # the peak-RSS mark from here
    baseline = memory_kb("VmRSS")
    cpu_started = time.process_time()
    run_export(export_request(recording, out, filters=filters.split(","), overwrite=True), load_session)
    print(baseline, memory_kb("VmHWM"), time.process_time() - cpu_started)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", default="10,60", help="session lengths in minutes (default 10,60)")
    parser.add_argument("--filters", default="ahf,hf,ecf")
    parser.add_argument("--out", default="parquet", choices=["parquet", "csv", "xlsx"])
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_export_memory.") as folder:
        for minutes in [float(m) for m in args.minutes.split(",")]:
            recording = Path(folder) / f"{minutes:g}min.gsrec"
            subprocess.run([sys.executable, "-m", "groundstation", "simulate", "--scenario", "flight", "--duration",
                            str(60 * minutes), "--out", str(recording)], check=True, env=env, capture_output=True)
            out = Path(folder) / f"{minutes:g}min.{args.out}"
            result = subprocess.run([sys.executable, __file__, "--filters", args.filters, "--child", str(recording), str(out),
                                     args.filters], check=True, env=env, capture_output=True, text=True)
            baseline_kb, peak_kb, cpu_s = result.stdout.split()
            rows.append((minutes, int(baseline_kb) / 1024, (int(peak_kb) - int(baseline_kb)) / 1024, float(cpu_s)))
            recording.unlink()
            out.unlink()
    print(f"Export to {args.out} with --filters {args.filters}\n")
    print("| session | RSS after imports (MB) | peak beyond the libraries (MB) | export CPU s |\n|---|---:|---:|---:|")
    for minutes, baseline_mb, beyond_mb, cpu_s in rows:
        print(f"| {minutes:g} min | {baseline_mb:.0f} | {beyond_mb:.0f} | {cpu_s:.1f} |")
    if len(rows) > 1:
        (m0, _, b0, _), (m1, _, b1, _) = rows[0], rows[-1]
        print(f"\nMB per hour of session (slope {m0:g} -> {m1:g} min): {(b1 - b0) / ((m1 - m0) / 60):.0f}")


if __name__ == "__main__":
    main()

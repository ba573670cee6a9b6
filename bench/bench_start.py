"""How long the app's estimators take to be compiled or loaded at a start (what a splash waited for before
a first start compiled in another process, bench/bench_first_data.py): the first start after an install,
the second, and the start after the package is installed again (what a test command that installs it does).

Each start is a new process that imports the estimators and makes every live one (``create``: the
numba kernels compiled, or loaded from the cache). The package is "installed" by copying its sources
into a fresh folder (new files, new times, no ``__pycache__``), as pip does; the user's cache folder
(``XDG_CACHE_HOME``) is a temporary one that survives the re-install. Baseline: the same cycle on the
``main`` branch's sources, whose numba cache sits in ``__pycache__`` beside them.

    python bench/bench_start.py [--cycles 3] [--baseline main]   # writes bench/bench_start.out.md
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("groundstation", "firmware_protocol")
# Wall time and the process's CPU time: on a shared, loaded machine the wall time mostly waits for a CPU,
# the CPU time is what the start costs.
START = ("import time; t0, c0 = time.perf_counter(), time.process_time(); "
         "from groundstation.estimation import create, live_estimators; [create(n) for n in live_estimators()]; "
         "print(time.perf_counter() - t0, time.process_time() - c0)")


def install(source: Path, site: Path) -> None:
    """The packages copied afresh into ``site``, as a re-install leaves them (no compiled files)."""
    for name in PACKAGES:
        shutil.rmtree(site / name, ignore_errors=True)
        shutil.copytree(source / name, site / name, ignore=shutil.ignore_patterns("__pycache__"))


def start_s(site: Path, cache: Path) -> tuple[float, float]:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(site), XDG_CACHE_HOME=str(cache))
    out = subprocess.run([sys.executable, "-c", START], env=env, cwd=site, capture_output=True, text=True, check=True)
    wall, cpu = out.stdout.split()[-2:]
    return float(wall), float(cpu)


def cycle(source: Path, work: Path) -> dict[str, tuple[float, float]]:
    site, cache = work / "site", work / "cache"
    shutil.rmtree(work, ignore_errors=True)
    site.mkdir(parents=True)
    install(source, site)
    first = start_s(site, cache)
    second = start_s(site, cache)
    install(source, site)
    return {"first start": first, "second start": second, "after a re-install": start_s(site, cache)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=3)
    parser.add_argument("--baseline", default="main", help="git ref of the baseline sources")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        baseline = tmp / "baseline"
        baseline.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline, *PACKAGES], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(baseline)], input=archive.stdout, check=True)
        runs = {name: [cycle(source, tmp / name) for _ in range(args.cycles)] for name, source in
                ((f"baseline ({args.baseline}: cache in __pycache__)", baseline), ("this branch (user cache folder)", ROOT))}
    lines = ["# Start: the live estimators ready (bench/bench_start.py)", "",
             f"Median of {args.cycles} cycles (install, start, start, re-install, start): CPU seconds of the "
             f"starting process (wall seconds in brackets); load average at the end {os.getloadavg()[0]:.1f} "
             f"on {os.cpu_count()} CPUs.", "",
             "| sources | first start | second start | after a re-install |", "|---|---|---|---|"]
    for name, cycles in runs.items():
        cells = [(statistics.median(c[k][1] for c in cycles), statistics.median(c[k][0] for c in cycles)) for k in cycles[0]]
        lines.append(f"| {name} | " + " | ".join(f"{cpu:.2f} ({wall:.1f})" for cpu, wall in cells) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    (ROOT / "bench" / "bench_start.out.md").write_text(text)


if __name__ == "__main__":
    main()

"""Warm start of the app to its first frame: ``groundstation app --demo`` against ``python -c pass`` and
``python -c "import PySide6.QtWidgets"``, in the same run.

Two moments of the app's process (``groundstation/ui/first_frame.py``, ``GROUNDSTATION_FIRST_FRAME=1``):
``first paint``, the main window's first paint event, and ``first data``, the first paint after the live
view drew a sample of the simulated bridge; CPU seconds of the whole process (every thread) since it
started, so other work on the machine weighs less than on a wall clock. The baselines' figure is their
whole process's CPU time. Warm: one start before the measured ones fills the numba cache (the user's cache
folder), the byte-code cache (as an installed package has it; PYTHONDONTWRITEBYTECODE is dropped) and the
page cache. Qt renders offscreen; settings and recordings go to a temporary folder.

    python bench/bench_first_frame.py [--repeats 7]     # from the worktree root; prints a Markdown table
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile

BASELINES = {"python -c pass": ["-c", "pass"], 'python -c "import PySide6.QtWidgets"': ["-c", "import PySide6.QtWidgets"]}
APP = ["-m", "groundstation", "app", "--demo"]
MOMENTS = ("first paint", "first data")


def run(argv: list[str], env: dict[str, str]) -> tuple[float, dict[str, float]]:
    """The child's CPU seconds (user + system) and the moments it printed."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, *argv], env=env, capture_output=True, text=True, check=True, timeout=600).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    moments = {}
    for line in out.splitlines():
        name, _, value = line.rpartition(" ")
        if name in MOMENTS:
            moments[name] = float(value)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), moments


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as home:
        env = {**{k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}, "PYTHONPATH": os.getcwd(), "QT_QPA_PLATFORM": "offscreen", "GROUNDSTATION_FIRST_FRAME": "1",
               "XDG_CONFIG_HOME": os.path.join(home, "config"), "GROUNDSTATION_RECORDINGS": os.path.join(home, "recordings"),
               "XDG_CACHE_HOME": os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache"))}  # the warm numba cache
        print(f"| process | CPU s to first paint | CPU s to first data | CPU s in all (median of {args.repeats}) |")
        print("|---|---|---|---|")
        for label, argv in BASELINES.items():
            run(argv, env)  # warm the page cache
            total = statistics.median(run(argv, env)[0] for _ in range(args.repeats))
            print(f"| {label} (baseline) | | | {total:.3f} |", flush=True)
        run(APP, env)  # warm: the numba cache filled, the files in the page cache
        runs = [run(APP, env) for _ in range(args.repeats)]
        paint, data = (statistics.median(m[name] for _, m in runs) for name in MOMENTS)
        total = statistics.median(t for t, _ in runs)
        print(f"| groundstation app --demo | {paint:.3f} | {data:.3f} | {total:.3f} |")
        print(f"\nload average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")


if __name__ == "__main__":
    main()

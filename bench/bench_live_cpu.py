"""The live window's CPU and memory (issue 35): ``groundstation app --demo`` in a real X server (an Xvfb
of its own) against ``groundstation record --port sim:`` headless, the same simulated source (the demo's:
100 Hz, magnetometer, barometer and GPS) and the same estimators (the app's ten live ones, ``record``'s
default), for ``--minutes`` each, one after the other, interleaved, ``--repeats`` times.

    python bench/bench_live_cpu.py [--minutes 2] [--repeats 2] [--tree PATH ...] [--commands app,record] [--together] [--display :N]   # from the worktree root

Figures of the whole process (every thread) from ``/proc/PID``: CPU seconds (user + system, its waited
children too) and RSS, at the first minute and at the end; "steady" is the CPU from the first minute to
the end as a share of one core (the start, imports and the estimators' kernels loaded, left out), "whole"
since the process started; the RSS at 10 minutes too when the runs are longer (the live tables hold 10
minutes of rows: ``session_parts.table.LIVE_KEEP_ROWS``). The app runs with fresh settings (the window's defaults: the Attitude tab,
the 30 s window), Qt on the X server (``QT_QPA_PLATFORM=xcb``, software rendering as on a machine
without a GPU); recordings go to a temporary folder. ``--tree`` runs each command from another
checkout as well (the code before a change, say), interleaved with this one's; ``--together`` runs the
trees' same command at the same time instead (both under the same load: long runs, where the load changes
between one and the next). ``--display :N``: the Xvfb on that display number (else the first free one).
Prints Markdown: the medians, and the app's over ``record``'s.
"""

from __future__ import annotations

import argparse
import os
from concurrent.futures import ThreadPoolExecutor
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TICK_S = os.sysconf("SC_CLK_TCK")
COMMANDS = {"app": ["app", "--demo"], "record": ["record", "--port", "sim:"]}
FIRST_S = 60.0  # the first checkpoint


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of ``pid`` and its waited-for children (/proc/PID/stat)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return sum(int(f) for f in fields[11:15]) / TICK_S  # utime, stime, cutime, cstime


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f"no VmRSS for {pid}")


class Xvfb:
    """An X server of its own, on ``display`` (":N") or the first free display (``-displayfd``)."""

    def __init__(self, display: str | None = None):
        self.display = display

    def __enter__(self) -> str:
        read, write = os.pipe()
        self.process = subprocess.Popen(["Xvfb", *([self.display] if self.display else []), "-displayfd", str(write), "-screen", "0",
                                         "1280x800x24", "-nolisten", "tcp"], pass_fds=(write,), stderr=subprocess.DEVNULL)
        os.close(write)
        with os.fdopen(read) as pipe:
            number = pipe.readline().strip()
        if not number:
            raise RuntimeError("Xvfb did not start")
        return f":{number}"

    def __exit__(self, *exc) -> None:
        self.process.terminate()
        self.process.wait(timeout=30)


def run(tree: Path, kind: str, seconds: float, display: str) -> dict[str, float]:
    """One run of ``kind`` from ``tree`` for ``seconds``: CPU and RSS at the first minute and the end."""
    with tempfile.TemporaryDirectory() as home:
        env = {**os.environ, "PYTHONPATH": str(tree), "XDG_CONFIG_HOME": f"{home}/config",
               "GROUNDSTATION_RECORDINGS": f"{home}/recordings", "DISPLAY": display, "QT_QPA_PLATFORM": "xcb"}
        argv = [sys.executable, "-m", "groundstation", *COMMANDS[kind]]
        if kind == "record":
            argv += ["--recordings", f"{home}/recordings", "--duration", str(seconds + 30)]  # stopped by us, as the app
        process = subprocess.Popen(argv, cwd=tree, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        started = time.monotonic()
        figures = {}
        try:
            for name, at_s in (("first", FIRST_S), *((("ten", 600.0),) if seconds > 600.0 else ()), ("end", seconds)):
                while time.monotonic() - started < at_s:
                    if process.poll() is not None:
                        raise RuntimeError(f"{kind} ended early ({process.returncode}): {process.stderr.read()[-2000:]}")
                    time.sleep(0.5)
                figures[f"cpu_{name}_s"], figures[f"rss_{name}_mb"] = cpu_s(process.pid), rss_mb(process.pid)
                figures[f"wall_{name}_s"] = time.monotonic() - started
        finally:
            process.terminate()
            try:
                process.wait(timeout=120)
            except subprocess.TimeoutExpired:  # its figures stand (read before); the hang is said
                process.kill()
                print(f"  {tree.name} {kind} did not end within 120 s of SIGTERM: killed", flush=True)
    figures["steady_pct"] = 100 * (figures["cpu_end_s"] - figures["cpu_first_s"]) / (figures["wall_end_s"] - figures["wall_first_s"])
    figures["whole_pct"] = 100 * figures["cpu_end_s"] / figures["wall_end_s"]
    return figures


def mb(value: float | None) -> str:
    return "–" if value is None else f"{value:.0f} MB"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", type=float, default=2.0, help="each run's length (default 2; at least 1.5)")
    parser.add_argument("--repeats", type=int, default=2, help="interleaved runs of each (default 2)")
    parser.add_argument("--tree", type=Path, action="append", default=[], help="another checkout to run as well")
    parser.add_argument("--commands", default=",".join(COMMANDS), help="which of them (default: app,record)")
    parser.add_argument("--together", action="store_true", help="each command of every tree at the same time")
    parser.add_argument("--display", default=None, help="the Xvfb's display, :N (default: the first free one)")
    args = parser.parse_args()
    kinds = args.commands.split(",")
    seconds = max(args.minutes, 1.5) * 60
    trees = [ROOT, *(t.resolve() for t in args.tree)]
    results: dict[tuple[Path, str], list[dict]] = {(t, k): [] for t in trees for k in kinds}
    print(f"{args.repeats} interleaved runs of {seconds / 60:g} min each; load average at the start "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}", flush=True)
    for tree in trees:  # numba's cache (per source path) filled and the byte code written, unmeasured
        with tempfile.TemporaryDirectory() as folder:
            subprocess.run([sys.executable, "-m", "groundstation", "record", "--port", "sim:", "--duration", "3", "--recordings", folder],
                           cwd=tree, env={**os.environ, "PYTHONPATH": str(tree)}, check=True, capture_output=True)
    # Each step: the runs made at once (every tree's with --together, else one).
    steps = ([[(tree, kind) for tree in trees] for kind in kinds] if args.together else [[(tree, kind)] for tree in trees for kind in kinds])
    with Xvfb(args.display) as display, ThreadPoolExecutor(len(trees)) as pool:
        for repeat in range(args.repeats):
            for step in steps:
                for (tree, kind), figures in zip(step, pool.map(lambda run_of: run(*run_of, seconds, display), step)):
                    results[tree, kind].append(figures)
                    print(f"  run {repeat + 1} {tree.name} {kind}: steady {figures['steady_pct']:.1f} %, whole {figures['whole_pct']:.1f} %, "
                          f"RSS {figures['rss_first_mb']:.0f} -> {mb(figures.get('rss_ten_mb'))} (10 min) -> {figures['rss_end_mb']:.0f} MB", flush=True)
    print(f"\nload average at the end {' '.join(f'{x:.1f}' for x in os.getloadavg())}\n")
    print("| tree | command | CPU from 1 min to the end, % of a core | CPU since the start | RSS at 1 min | at 10 min | at the end |")
    print("|---|---|---|---|---|---|---|")
    median = {key: {f: statistics.median(r[f] for r in runs) for f in runs[0]} for key, runs in results.items()}
    for (tree, kind), m in median.items():
        print(f"| {tree.name} | `{' '.join(COMMANDS[kind])}` | {m['steady_pct']:.1f} % | {m['whole_pct']:.1f} % "
              f"| {m['rss_first_mb']:.0f} MB | {mb(m.get('rss_ten_mb'))} | {m['rss_end_mb']:.0f} MB |")
    print()
    for tree in trees if set(kinds) == set(COMMANDS) else ():
        app, record = median[tree, "app"], median[tree, "record"]
        print(f"{tree.name}: the app over record, CPU from 1 min: {app['steady_pct'] / record['steady_pct']:.2f}x; "
              f"since the start {app['whole_pct'] / record['whole_pct']:.2f}x; RSS at the end {app['rss_end_mb'] / record['rss_end_mb']:.2f}x, "
              f"the app's RSS from 1 min to the end {app['rss_end_mb'] - app['rss_first_mb']:+.0f} MB")


if __name__ == "__main__":
    main()

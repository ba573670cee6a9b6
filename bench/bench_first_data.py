"""The first data of a first start (issue 34): ``groundstation app --demo``, ``groundstation record
--port sim:``, ``groundstation app FILE`` (a shared flight log opened before any live start) and
``groundstation export FILE`` with numba's cache EMPTY (``NUMBA_CACHE_DIR`` a fresh temporary folder for
each run, as after an install) against the warm start (the cache filled), in the same run.

The moments: ``first data`` of the process's stopwatch (``groundstation/stopwatch.py``,
``GROUNDSTATION_FIRST_FRAME=1``): the app's first paint with a curve on screen (the simulated bridge's;
then it closes itself), ``record``'s first IMU sample with every estimator's estimate in its tables; and
for a file shown without estimators not compiled yet, ``every estimator``: once they all joined it (then
the app closes itself). CPU seconds of the whole process (every thread) since it started. "CPU s in all"
is the process and its children (the background compiler, stopped when the process ends) until it ended:
the app at its first data (a file: every estimator), ``record`` after ``--duration``, ``export`` when
written. Also said: how many estimators were not compiled at the first data (their kernels compiling in
the other process). Qt renders offscreen; settings and recordings go to a temporary folder.
``--only TEXT`` measures the commands whose label holds TEXT.

Close during that compile (``--ctrl-c S``): ``app FILE`` Ctrl-C'd S seconds after its start, the wall and CPU
seconds to its exit, with an empty cache and a warm one.

Why a file's estimators are not run interpreted meanwhile (``--interpreted``): each live estimator's batch
run with its kernel's source interpreted against compiled, a sample's cost and an hour's at 100 Hz.

The alternative to a compiling process: a compiling thread. ``--alternatives`` measures what it costs
the process's other threads: the longest pause of a 10 ms tick in the main thread (as the window's
redraw timer and the reader thread need the GIL) while ahf2's kernel compiles in a thread, and while it
compiles in a process (``estimation.warm_up.WarmUp``).

Install time instead (``--portable``): numba's only portable cache is one compiled for a generic CPU
(``NUMBA_CPU_NAME=generic``). Whether a process finds ahf2's kernel in such a cache, with the host's CPU
and with the generic one named, what it then costs to have it ready, and its speed in ``run``.

    python bench/bench_first_data.py [--repeats 3] [--only TEXT] [--alternatives] [--portable] [--interpreted] [--ctrl-c S]
    # from the worktree root; prints Markdown
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from groundstation.stopwatch import UNCOMPILED  # noqa: E402

LOG = Path("/work/shared/datasets/flightlogs/px4_fmuv5_quad_hop.ulg")  # a shared flight log: 8 estimators, 2 min
COMMANDS = {
    "groundstation app --demo": ["-m", "groundstation", "app", "--demo"],
    "groundstation record --port sim: --duration 3": ["-m", "groundstation", "record", "--port", "sim:", "--duration", "3"],
    f"groundstation app {LOG.name}": ["-m", "groundstation", "app", str(LOG)],
    f"groundstation export {LOG.name}": ["-m", "groundstation", "export", str(LOG), "--out", "{home}/out.csv", "--overwrite"],
    f"groundstation export {LOG.name} --filters ahf2": ["-m", "groundstation", "export", str(LOG), "--filters", "ahf2", "--out",
                                                         "{home}/out.csv", "--overwrite"],
}
FILL = ["-c", "import numpy as np; from groundstation.estimation import create, live_estimators; "
              "[create(n).run(np.zeros((1, 3)), np.zeros((1, 3)), np.ones(1)) for n in live_estimators()]"]


def run(argv: list[str], env: dict[str, str]) -> tuple[float, float, float, int]:
    """(CPU s to the first data, CPU s to every estimator in the window, CPU s in all, estimators not compiled at
    the first data); NaN for a moment the command does not have (an export has no first data)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, *argv], env=env, capture_output=True, text=True, check=True, timeout=1800).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    lines = out.splitlines()
    first, every = (next((float(line.split()[-1]) for line in lines if line.startswith(moment)), math.nan)
                    for moment in ("first data ", "every estimator "))
    uncompiled = next((line.removeprefix(UNCOMPILED).strip() for line in lines if line.startswith(UNCOMPILED)), "")
    total = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return first, every, total, len([name for name in uncompiled.split(",") if name])


def row(label: str, runs: list[tuple[float, float, float, int]]) -> str:
    first, every, total, uncompiled = (statistics.median(r[i] for r in runs) for i in range(4))
    return f"| {label} | {first:.2f} | {every:.2f} | {total:.2f} | {uncompiled:.0f} |".replace("nan", "—")


def first_data(repeats: int, only: str | None) -> None:
    with tempfile.TemporaryDirectory() as home:
        home = Path(home)
        base = {**{k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}, "PYTHONPATH": str(ROOT),
                "QT_QPA_PLATFORM": "offscreen", "GROUNDSTATION_FIRST_FRAME": "1", "XDG_CONFIG_HOME": str(home / "config"),
                "GROUNDSTATION_RECORDINGS": str(home / "recordings")}
        warm = {**base, "NUMBA_CACHE_DIR": str(home / "warm")}
        subprocess.run([sys.executable, *FILL], env=warm, check=True)  # the warm start's cache
        print(f"| command, numba cache | CPU s to first data | CPU s to every estimator | CPU s in all | "
              f"estimators not compiled at first data (median of {repeats}) |")
        print("|---|---|---|---|---|")
        for n, (label, argv) in enumerate(COMMANDS.items()):
            if only is not None and only not in label:
                continue
            argv = [arg.format(home=home) for arg in argv]
            run(argv, warm)  # byte code and page cache
            runs = {"empty": [], "warm": []}
            for k in range(repeats):  # interleaved: the machine's load weighs on both alike
                runs["empty"].append(run(argv, {**base, "NUMBA_CACHE_DIR": str(home / f"cold{n}-{k}")}))
                runs["warm"].append(run(argv, warm))
            for cache, measured in runs.items():
                print(row(f"{label}, {cache}", measured), flush=True)
        print(f"\nload average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")


def longest_pause_s(work, seconds_after: float = 0.0) -> tuple[float, float]:
    """The longest interval between 10 ms ticks of this thread while ``work()`` (started) runs; and its wall time."""
    import threading

    done = threading.Event()
    t0 = time.perf_counter()
    handle = work(done)
    longest, last = 0.0, time.perf_counter()
    while not done.is_set():
        time.sleep(0.01)
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    if handle is not None:
        handle()
    return longest, time.perf_counter() - t0


def alternatives() -> None:
    import threading

    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="bench-thread-")
    from groundstation.estimation import create
    from groundstation.estimation.warm_up import WarmUp

    def in_thread(done):
        threading.Thread(target=lambda: (create("ahf2"), done.set()), daemon=True).start()

    def in_process(done):
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="bench-process-")
        warm = WarmUp(["ahf2"])

        def watch():
            while "ahf2" not in warm.compiled:
                time.sleep(0.01)
            done.set()

        threading.Thread(target=watch, daemon=True).start()
        return warm.stop

    print("| ahf2's kernel compiled in | longest pause of a 10 ms tick in the main thread, s | wall s |")
    print("|---|---|---|")
    for label, work in (("a thread", in_thread), ("a process (WarmUp)", in_process)):
        longest, wall = longest_pause_s(work)
        print(f"| {label} | {longest:.3f} | {wall:.1f} |", flush=True)


PORTABLE = """
import sys, time
import numpy as np
from groundstation.estimation import create
from groundstation.estimation.ahf2 import Ahf2
from groundstation.estimation.base import KERNEL_SIGNATURE, _loaded
t = time.process_time()
found = _loaded(Ahf2.kernel, KERNEL_SIGNATURE)
t_ready = time.process_time() - t
t = time.process_time()
estimator = create("ahf2")
t_ready += time.process_time() - t
rows = 200_000
gyr, acc = np.random.default_rng(1).normal(0, 0.1, (rows, 3)), np.tile([0.0, 0.0, -1.0], (rows, 1))
estimator.run(gyr[:10], acc[:10], 0.01)
t = time.process_time()
estimator.run(gyr, acc, 0.01)
print(found, t_ready, (time.process_time() - t) / rows * 1e9)
"""


def portable() -> None:
    print("| ahf2's kernel: cache made for, process run as | found in the cache | CPU s to have it ready | run, ns a sample |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as home:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        for made, run_as in (("generic", "generic"), ("generic", "host"), ("generic", "generic"), ("host", "host"), ("host", "host")):
            cpu = {"NUMBA_CPU_NAME": "generic"} if run_as == "generic" else {}
            out = subprocess.run([sys.executable, "-c", PORTABLE], env={**env, **cpu, "NUMBA_CACHE_DIR": os.path.join(home, made)},
                                 capture_output=True, text=True, check=True).stdout.split()
            print(f"| {made}, {run_as} | {out[0]} | {float(out[1]):.2f} | {float(out[2]):.0f} |", flush=True)


def ctrl_c(after_s: float) -> None:
    """``app LOG`` with an empty cache, Ctrl-C ``after_s`` later (its kernels compiling in the other process), and
    with a warm one: wall and CPU s from the signal to its exit (the app's and its compiler's)."""
    import signal

    def cpu_s(pid: int) -> float:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    print("| numba cache | Ctrl-C to exit, wall s | Ctrl-C to exit, CPU s | load average |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as home:
        base = {**os.environ, "PYTHONPATH": str(ROOT), "QT_QPA_PLATFORM": "offscreen", "XDG_CONFIG_HOME": f"{home}/config",
                "GROUNDSTATION_RECORDINGS": f"{home}/recordings"}
        subprocess.run([sys.executable, *FILL], env={**base, "NUMBA_CACHE_DIR": f"{home}/warm"}, check=True)
        for cache in ("empty", "warm"):
            app = subprocess.Popen([sys.executable, "-m", "groundstation", "app", str(LOG)], env={**base, "NUMBA_CACHE_DIR": f"{home}/{cache}"},
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(after_s)
            children = subprocess.run(["pgrep", "-P", str(app.pid)], capture_output=True, text=True).stdout.split()
            before = cpu_s(app.pid) + sum(cpu_s(int(c)) for c in children if Path(f"/proc/{c}").exists())  # reaped at its exit
            t = time.monotonic()
            app.send_signal(signal.SIGINT)
            _, _, usage = os.wait4(app.pid, 0)
            print(f"| {cache} | {time.monotonic() - t:.2f} | {usage.ru_utime + usage.ru_stime - before:.2f} | {os.getloadavg()[0]:.1f} |",
                  flush=True)


INTERPRETED_SAMPLES = 2000


def interpreted() -> None:
    """Each live estimator's ``run``, its kernel's source interpreted (as a first start would have to run it over
    a file while the kernel compiles) against compiled: ns a sample, and what an hour at 100 Hz would take."""
    import numpy as np

    from groundstation.estimation import ESTIMATORS, create, live_estimators
    from groundstation.estimation.base import CompiledEstimator

    rng = np.random.default_rng(1)
    gyr, acc = rng.normal(0, 0.1, (INTERPRETED_SAMPLES, 3)), np.tile([0.0, 0.0, -1.0], (INTERPRETED_SAMPLES, 1))
    print("| estimator | interpreted, µs a sample | compiled, µs a sample | an hour at 100 Hz interpreted, CPU s |")
    print("|---|---|---|---|")
    for name in live_estimators():
        cls = ESTIMATORS[name]
        if not issubclass(cls, CompiledEstimator):
            continue
        compiled = create(name)
        compiled.run(gyr[:10], acc[:10], 0.01)
        times = []
        for estimator in (cls(dtype=np.float64), compiled):
            t = time.process_time()
            estimator.run(gyr, acc, 0.01)
            times.append((time.process_time() - t) / INTERPRETED_SAMPLES)
        print(f"| {name} | {times[0] * 1e6:.1f} | {times[1] * 1e6:.2f} | {times[0] * 360_000:.0f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", metavar="TEXT", help="only the commands whose label holds TEXT")
    parser.add_argument("--interpreted", action="store_true", help="interpreted kernels over a file against compiled")
    parser.add_argument("--ctrl-c", type=float, metavar="S", help="Ctrl-C the app on a file S seconds after its start")
    parser.add_argument("--alternatives", action="store_true", help="a compiling thread against a compiling process")
    parser.add_argument("--portable", action="store_true", help="a cache made for a generic CPU (install time)")
    args = parser.parse_args()
    if args.alternatives:
        alternatives()
    elif args.portable:
        portable()
    elif args.interpreted:
        interpreted()
    elif args.ctrl_c is not None:
        ctrl_c(args.ctrl_c)
    else:
        first_data(args.repeats, args.only)


if __name__ == "__main__":
    main()

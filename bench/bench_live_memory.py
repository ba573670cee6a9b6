"""Memory of a long live session (defect 13): 100 Hz simulated frames through the live session and the
window's plot model, faster than real time, RSS at checkpoints; bounded (as the app runs) and the
baseline (the bounds off: every table row kept, the plot history never merged).

    python bench/bench_live_memory.py [--minutes 10,60] [--filters ahf]
    python bench/bench_live_memory.py --where S
    python bench/bench_live_memory.py --window [--minutes 5,10,20,30] [--tree PATH ...]

``--where S``: where the memory goes first: S simulated seconds through the pipeline with the app's
estimators under ``tracemalloc`` (the Python heap by file), and each table's bytes per minute.

Each run is a fresh process: the simulated bridge's bytes (``sim:``, magnetometer, barometer and GPS,
as the demo) are read unpaced by a ``LiveSession`` (recording to a temporary folder, as the app does)
whose pipeline runs ``--filters``, while the main thread keeps a ``LiveView`` (offscreen; its
10-minute window, two channels on the Channels tab) refreshed. RSS after handing freed heap pages back
(``bench_ui.rss_mb``). The app's ten estimators (``--filters app``) make the imu table 102 columns wide
instead of 20 and run slower than real time on this machine; the bound is in rows, so the bounded RSS is
flat either way and the baseline's slope scales with the width.

``--window`` (issue 35: the app's RSS still grew from 10 to 20 minutes): the app's own window (``MainWindow``,
offscreen, its redraw timer running, the heap set up as ``ui.app.run`` does) on the demo's session with the
app's ten estimators, its source unpaced (about 10x real time here: the window draws fewer frames per simulated
minute than the app, the same rows); one process per tree (this checkout, and each ``--tree``: the code
before a change, say), all at once. RSS as the system counts it (no trim: as the app's), the C heap in use
and held free (glibc's ``mallinfo2``), the session's tables and the plot buffers.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
import tracemalloc
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pyqtgraph as pg  # noqa: E402
from PySide6 import QtCore, QtWidgets  # noqa: E402

from bench_ui import rss_mb  # noqa: E402
from groundstation.estimation import live_estimators  # noqa: E402
from groundstation.session_makers.factory import Sessions  # noqa: E402
from groundstation.session_makers.live import LiveSession  # noqa: E402
from groundstation.session_makers.pipeline import Pipeline  # noqa: E402
from groundstation.session_parts.table import LIVE_KEEP_ROWS  # noqa: E402
from groundstation.sim.stream import SimStream  # noqa: E402
from groundstation.sources.base import Chunk, SourceClosed  # noqa: E402
from groundstation.sources.sim import parse_scenario  # noqa: E402
from groundstation.sources.spec import parse_spec  # noqa: E402
from groundstation.ui import series as series_module  # noqa: E402
from groundstation.ui import app as app_module  # noqa: E402
from groundstation.ui.live_view import LiveView  # noqa: E402
from groundstation.ui.main_window import MainWindow  # noqa: E402

STEP_S = 0.5  # simulated seconds of frames per read


class UnpacedSim:
    """The simulated bridge's bytes as fast as they are made, presented as a live link (recorded)."""

    is_replay = False
    can_reopen = False
    can_send = False
    protocol = "gs"
    description = "simulated bridge, unpaced"

    def __init__(self, duration_s: float):
        self.stream = SimStream(parse_scenario(parse_spec(f"sim:?duration={duration_s}")))
        self.duration_s = duration_s
        self._t_s = 0.0
        self._pending: list = []

    def read(self) -> Chunk | None:
        while not self._pending:
            if self._t_s >= self.duration_s:
                raise SourceClosed
            self._t_s += STEP_S
            self._pending = self.stream.advance(self._t_s)
        chunk = self._pending.pop(0)
        return Chunk(int(chunk.t_s * 1e9), chunk.data)

    def close(self) -> None:
        self._t_s = self.duration_s


def table_mb(pipeline: Pipeline) -> float:
    """The rows the session's tables hold now."""
    tables = [*pipeline.tables.values(), pipeline.link.per_second]
    return sum(len(t.array()) * len(t.columns) * 8 for t in tables) / 1e6


def child(kind: str, minutes: list[float], filters: tuple[str, ...]) -> None:
    app = QtWidgets.QApplication([])
    if kind == "baseline":
        series_module.HISTORY_BINS = 1 << 40  # the plot history never merged, as before
    pipeline = Pipeline(filters, keep_rows=LIVE_KEEP_ROWS if kind == "bounded" else None)
    view = LiveView()
    view.window_box.setCurrentText("10 min")
    view.channels.restore_layout('[["imu.gyr_x_rad_s"], ["baro.pressure_Pa"]]')
    with tempfile.TemporaryDirectory() as folder:
        session = LiveSession(UnpacedSim(60.0 * max(minutes) + 1.0), pipeline, recordings_dir=Path(folder))
        view.set_session(session)
        checkpoints = [0.0, *sorted(minutes)]
        started = time.monotonic()
        with session:
            while checkpoints:
                app.processEvents()
                view.refresh()
                done_min = (len(pipeline.imu) / 100.0) / 60.0
                if done_min >= checkpoints[0] or not session.running:
                    with session.lock:
                        rss, tables = rss_mb(), table_mb(pipeline)
                    plots = sum(s.nbytes() for s in [*view.series.values(), *view.channels.series.values()]) / 1e6
                    print(json.dumps({"kind": kind, "minutes": round(done_min, 2), "rss_mb": rss, "tables_mb": tables,
                                      "plots_mb": plots, "rows": len(pipeline.imu), "wall_s": time.monotonic() - started,
                                      "imu_columns": len(pipeline.imu.columns)}), flush=True)
                    checkpoints.pop(0)
                    if not session.running:
                        break
                time.sleep(0.05)
    view.close()


class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]


def heap_mb() -> tuple[float, float]:
    """(in use, held free) of glibc's heap, MB: every arena and the blocks mapped on their own."""
    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = MallInfo2
    info = libc.mallinfo2()
    return (info.uordblks + info.hblkhd) / 1e6, info.fordblks / 1e6


def plain_rss_mb() -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024


def window_child(minutes: list[float]) -> None:
    """The app's window on the demo's session, unpaced; a line of figures at each checkpoint."""
    getattr(app_module, "keep_large_blocks_out_of_the_heap", lambda: None)()  # as ``ui.app.run`` (none before issue 35)
    app = QtWidgets.QApplication([])
    pg.setConfigOptions(antialias=False)  # as ``ui.app.run``
    with tempfile.TemporaryDirectory() as folder:  # the recordings and settings, removed at the end

        class UnpacedSessions(Sessions):
            def open(self, spec, *, settings=None, recordings_dir=None, **defaults):
                pipeline = Pipeline(live_estimators(), settings, keep_rows=LIVE_KEEP_ROWS, compile_in_background=True)
                return LiveSession(UnpacedSim(60.0 * max(minutes) + 5.0), pipeline, recordings_dir=Path(folder))

        settings = QtCore.QSettings(f"{folder}/settings.ini", QtCore.QSettings.IniFormat)
        window = MainWindow(settings, UnpacedSessions())
        window.show()
        window.start_demo()
        session, checkpoints, started = window.session, sorted(minutes), time.monotonic()
        while checkpoints:
            app.processEvents()
            time.sleep(0.005)
            done_min = len(session.pipeline.imu) / 100.0 / 60.0
            if done_min >= checkpoints[0] or not session.running:  # a run ended early: its last figures
                with session.lock:
                    in_use, free = heap_mb()
                    view = window.live_view
                    print(json.dumps({"kind": os.environ.get("TREE", "?"), "minutes": round(done_min, 2),
                                      "rss_mb": plain_rss_mb(), "heap_mb": in_use, "free_mb": free, "tables_mb": table_mb(session.pipeline),
                                      "plots_mb": sum(s.nbytes() for s in [*view.series.values(), *view.channels.series.values()]) / 1e6,
                                      "wall_s": time.monotonic() - started}), flush=True)
                checkpoints = [] if not session.running else checkpoints[1:]
        window.close()


def window_runs(minutes: str, trees: list[Path]) -> None:
    print(f"the app's window, unpaced demo; checkpoints at {minutes} simulated minutes")
    runs = [subprocess.Popen([sys.executable, __file__, "--child", "window", "--minutes", minutes], stdout=subprocess.PIPE, text=True,
                             env={**os.environ, "PYTHONPATH": str(tree), "TREE": tree.name}) for tree in trees]
    rows = [json.loads(line) for run in runs for line in run.stdout if line.startswith("{")]
    for run in runs:
        run.wait()
    print("| tree | simulated minutes | RSS | C heap in use | held free | tables | plot buffers | wall |")
    print("|---|---|---|---|---|---|---|---|")
    for row in sorted(rows, key=lambda r: (r["kind"], r["minutes"])):
        print(f"| {row['kind']} | {row['minutes']:.1f} | {row['rss_mb']:.1f} MB | {row['heap_mb']:.1f} MB | {row['free_mb']:.1f} MB "
              f"| {row['tables_mb']:.1f} MB | {row['plots_mb']:.1f} MB | {row['wall_s']:.0f} s |")


def where(seconds: float) -> None:
    """The Python heap by file after ``seconds`` of the app's session, and each table's share."""
    source = UnpacedSim(seconds)
    pipeline = Pipeline(live_estimators())
    tracemalloc.start()
    try:
        while True:
            chunk = source.read()
            pipeline.feed(chunk.t_host_ns, chunk.data)
    except SourceClosed:
        pass
    heap = tracemalloc.take_snapshot().statistics("filename")
    total = sum(s.size for s in heap)
    print(f"where: {seconds:g} s of the app's session ({len(pipeline.imu)} IMU rows), Python heap {total / 1e6:.1f} MB:")
    for stat in heap[:4]:
        print(f"  {stat.size / 1e6:6.2f} MB ({100 * stat.size / total:4.1f} %) {Path(stat.traceback[0].filename).relative_to(Path.cwd().parent) if Path.cwd().parent in Path(stat.traceback[0].filename).parents else stat.traceback[0].filename}")
    minutes = len(pipeline.imu) / 100.0 / 60.0
    for name, table in sorted(pipeline.tables.items(), key=lambda item: -len(item[1]) * len(item[1].columns)):
        if len(table):
            print(f"  table {name:9s} {len(table.columns):3d} columns, {len(table) * len(table.columns) * 8 / 1e6 / minutes:5.2f} MB a minute")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--minutes", default="10,60", help="checkpoints, simulated minutes (default: 10,60)")
    parser.add_argument("--filters", default="ahf", help="the pipeline's estimators, or 'app' for the app's (default: ahf)")
    parser.add_argument("--where", type=float, default=None, metavar="S", help="where the memory goes (tracemalloc), S seconds")
    parser.add_argument("--window", action="store_true", help="the app's window on the unpaced demo (issue 35)")
    parser.add_argument("--tree", type=Path, action="append", default=[], help="--window: another checkout to run as well")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.where:
        where(args.where)
        return
    minutes = [float(m) for m in args.minutes.split(",")]
    if args.child == "window":
        window_child(minutes)
        return
    if args.window:
        window_runs(args.minutes, [Path(__file__).resolve().parents[1], *(t.resolve() for t in args.tree)])
        return
    filters = live_estimators() if args.filters == "app" else tuple(args.filters.split(","))
    if args.child:
        child(args.child, minutes, filters)
        return
    print(f"{', '.join(filters)}; checkpoints at {args.minutes} simulated minutes of 100 Hz frames")
    # Both runs at once, each line printed as it comes (on a loaded machine an hour takes a while).
    runs = {kind: subprocess.Popen([sys.executable, __file__, "--child", kind, "--minutes", args.minutes, "--filters", args.filters],
                                   stdout=subprocess.PIPE, text=True) for kind in ("baseline", "bounded")}
    first: dict[str, dict] = {}
    lines = queue.Queue()
    for kind, run in runs.items():
        threading.Thread(target=lambda run=run: [lines.put(line) for line in run.stdout] + [lines.put(None)], daemon=True).start()
    ended = 0
    while ended < len(runs):
        line = lines.get()
        if line is None:
            ended += 1
            continue
        if not line.startswith("{"):
            continue
        row = json.loads(line)
        start = first.setdefault(row["kind"], row)
        print(f"{row['kind']:8s} {row['minutes']:6.1f} min ({row['rows']:7d} IMU rows, {row['imu_columns']} columns, "
              f"{row['wall_s']:5.0f} s wall): RSS {row['rss_mb']:6.1f} MB (+{row['rss_mb'] - start['rss_mb']:5.1f}), "
              f"tables {row['tables_mb']:6.1f} MB, plot buffers {row['plots_mb']:5.1f} MB", flush=True)

if __name__ == "__main__":
    main()

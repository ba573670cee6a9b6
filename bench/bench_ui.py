"""UI figures (offscreen Qt, software rendering): redraw cost, live CPU, memory over a long replay.

    python bench/bench_ui.py [--live-seconds S] [--hours H] [--skip-redraw] [--skip-live] [--skip-memory]

1. Redraw: the attitude plots (4 curves: AHF and onboard pitch and roll; 8 curves: with HF and ECF
   too) over a 60 s and a 10 min window of 100 Hz data from the simulator; per frame, as in the app:
   1/30 s of new rows taken, the plots drawn, and the paint Qt then does (of what changed: the newest
   samples' strip, the whole plots when a curve takes its head or the axis steps) in a 1000x700
   widget. CPU ms of the UI thread per frame (mean, over 4 s of frames, and median) with peak
   downsampling (as the app) and plain (4 curves); the 8-curve cost as a ratio to the 4-curve one.
2. Live: the main window for S s (default 60) on the in-process simulated bridge (the simulated
   aircraft's CPU included), then on bridge-sim through a pty (as a real USB bridge), both with the
   4 default curves, then the demo again with HF and ECF shown (8 curves): whole-process CPU %
   (reader, pipeline with the app's estimators, recorder, UI) and its split between the UI thread and
   the others, UI frames/s, median ms per redraw tick.
3. Memory: an H-hour (default 2) simulated flight, recorded as the app records (ahf, hf, ecf), is
   replayed as fast as possible, in fresh processes: headless, and into the window on its "whole
   session" window. The difference in RSS growth is what the UI costs beyond the session's data.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np  # noqa: E402
from PySide6 import QtCore, QtTest, QtWidgets  # noqa: E402

from groundstation.recording import open_recording  # noqa: E402
from groundstation.session_makers.pipeline import Pipeline  # noqa: E402
from groundstation.session_parts.table import Table  # noqa: E402
from groundstation.sim.stream import Scenario, SimStream  # noqa: E402
from groundstation.estimation import live_estimators  # noqa: E402
from groundstation.session_makers.factory import replay_session  # noqa: E402
from groundstation.sources import ReplaySource  # noqa: E402
from groundstation.ui.live_view import attitude_plots  # noqa: E402
from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow  # noqa: E402
from groundstation.ui.plots import StackedPlots  # noqa: E402
from groundstation.ui.series import Series, imu_quantities, onboard_quantities  # noqa: E402

FRAMES = 120  # 4 s of frames: the curves take their heads' samples in them (every second)


def rss_mb() -> float:
    """Resident memory after handing freed heap pages back to the OS (glibc keeps them otherwise,
    so RSS would also count the holes left by the large temporary arrays of a fast replay)."""
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024


def table_mb(pipeline: Pipeline) -> float:
    tables = [pipeline.imu, pipeline.onboard, pipeline.link.per_second, *pipeline.tables.values()]
    return sum(len(t) * len(t.columns) * 8 for t in tables) / 1e6


def simulated_table(seconds: float, filters: tuple[str, ...]) -> Pipeline:
    pipeline = Pipeline(filters)
    stream = SimStream(Scenario("flight", seconds + 5, seed=1))
    for chunk in stream.advance(seconds + 1.5):
        pipeline.feed(int(chunk.t_s * 1e9), chunk.data)
    return pipeline


def growing(table: Table, rows: np.ndarray) -> Table:
    copy = Table(table.columns)
    copy.append(rows.ravel().tolist())
    return copy


def bench_redraw() -> None:
    """Per frame, as in the app: 1/30 s of new 100 Hz rows, taken into the Series, drawn, painted."""
    filters = ("ahf", "hf", "ecf")
    pipeline = simulated_table(610.0, filters)
    imu_rows, onboard_rows = pipeline.imu.array(), pipeline.onboard.array()
    lock = threading.Lock()
    means = {}
    for shown in (filters[:1], filters):
        plots = StackedPlots(attitude_plots(shown))
        plots.resize(1000, 700)
        plots.show()
        QtTest.QTest.qWaitForWindowExposed(plots)  # an unexposed widget does not paint at all
        curves = len(plots.curves)
        for window_s in (60.0, 600.0):
            for mode in ("peak", None) if curves == 4 else ("peak",):
                for item in plots.items:
                    item.setDownsampling(auto=mode is not None, mode=mode or "peak", ds=1)
                start = int(np.searchsorted(imu_rows[:, 0], window_s + 2.0))
                imu, onboard = growing(pipeline.imu, imu_rows[:start]), growing(pipeline.onboard, onboard_rows[:start])
                series = {"imu": Series(imu, imu_quantities(filters)), "onboard": Series(onboard, onboard_quantities)}
                for s in series.values():
                    s.take(lock)
                plots.draw(series, window_s, None)  # the window chosen: everything drawn
                QtWidgets.QApplication.processEvents()
                times = []
                for frame in range(FRAMES):
                    rows = slice(start + 3 * frame, start + 3 * frame + 3)
                    imu.append(imu_rows[rows].ravel().tolist())
                    onboard.append(onboard_rows[rows].ravel().tolist())
                    t0 = time.thread_time()
                    grew = {name for name, s in series.items() if s.take(lock)}
                    plots.draw(series, window_s, grew)
                    QtWidgets.QApplication.processEvents()  # the paint Qt schedules, as the event loop does it
                    times.append(time.thread_time() - t0)
                ms = 1e3 * statistics.mean(times)
                means[curves, window_s, mode] = ms
                ratio = f"  ({ms / means[4, window_s, mode]:.2f}x the 4 curves)" if curves == 8 else ""
                points = len(series["imu"].data("ahf_pitch_deg", window_s)[0])
                print(f"redraw {curves} curves x {points:6d} points ({window_s:4.0f} s window), "
                      f"{'peak downsampling' if mode else 'plain            '}: {ms:5.2f} ms CPU/frame "
                      f"(median {1e3 * statistics.median(times):5.2f}; {3.0 * ms:4.1f} % of a core at 30 frames/s){ratio}")
        plots.close()


def bench_live(seconds: float) -> None:
    """The window on the in-process demo, then on bridge-sim through a pty (the aircraft in another
    process, as with a real USB bridge): whole-process CPU, UI frames/s, redraw tick."""
    bridge = subprocess.Popen([sys.executable, "-m", "groundstation", "bridge-sim", "--scenario", "flight"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        pty = bridge.stdout.readline().split()[-1]
        for label, start in (("simulated bridge in process (demo), 4 curves", lambda w: w.start_demo()),
                             ("bridge-sim on a pty (another process), 4 curves", lambda w: w.connect_serial(pty, 115200)),
                             ("simulated bridge in process (demo), 8 curves", demo_with_8_curves)):
            cpu, ui_cpu, frames, ticks = live_run(start, seconds)
            print(f"live 100 Hz, {label}, {seconds:.0f} s: CPU {cpu:.1f} % of one core (whole process; UI thread {ui_cpu:.1f}, "
                  f"other threads {cpu - ui_cpu:.1f}), {frames:.1f} UI frames/s, redraw tick median {1e3 * statistics.median(ticks):.1f} ms "
                  f"(p95 {1e3 * np.percentile(ticks, 95):.1f} ms; the paint follows the tick); load average {os.getloadavg()[0]:.1f}")
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)


def demo_with_8_curves(window: MainWindow) -> None:
    window.start_demo()
    for label in ("HF", "ECF"):
        window.live_view.set_visible(label, True)


def ui_thread_cpu_s() -> float:
    """CPU seconds of the main (UI) thread so far, from /proc (``time.process_time`` counts every thread)."""
    with open(f"/proc/self/task/{os.getpid()}/stat") as stat:
        fields = stat.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime


def live_run(start, seconds: float) -> tuple[float, float, float, list[float]]:
    with tempfile.TemporaryDirectory() as folder:
        settings = QtCore.QSettings(str(Path(folder) / "settings.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(settings, Sessions(), recordings_dir=Path(folder))
        window.resize(1280, 800)
        window.show()
        start(window)
        tick_times = []
        tick = window.tick

        def timed_tick():
            t0 = time.perf_counter()
            tick()
            tick_times.append(time.perf_counter() - t0)

        window.timer.timeout.disconnect()
        window.timer.timeout.connect(timed_tick)
        wait(2.0)  # past the board's boot second
        tick_times.clear()
        cpu0, ui0, wall0, frames0 = time.process_time(), ui_thread_cpu_s(), time.monotonic(), window.live_view.frames_drawn
        wait(seconds)
        cpu, ui, wall = time.process_time() - cpu0, ui_thread_cpu_s() - ui0, time.monotonic() - wall0
        frames = window.live_view.frames_drawn - frames0
        window.close()
    return 100 * cpu / wall, 100 * ui / wall, frames / wall, tick_times


def wait(seconds: float) -> None:
    """Run the event loop, as ``app.exec`` does, for ``seconds``."""
    loop = QtCore.QEventLoop()
    QtCore.QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()


def make_recording(path: Path, hours: float) -> None:
    from groundstation.recording import RecordingWriter

    duration_s = hours * 3600
    stream = SimStream(Scenario("flight", duration_s, seed=2))
    with RecordingWriter(path, {"source": "bench_ui", "filters": list(live_estimators())}) as writer:
        t = 0.0
        while t < duration_s:
            t += 60.0
            for chunk in stream.advance(t):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)


def bench_memory(hours: float) -> None:
    """Each replay in a fresh process, headless and into the window: the difference is the UI's."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "long.gsrec"
        t0 = time.monotonic()
        make_recording(path, hours)
        print(f"memory: simulated a {hours:g} h recording ({path.stat().st_size / 1e6:.0f} MB) in {time.monotonic() - t0:.0f} s")
        runs = {}
        for kind in ("headless", "window"):
            result = subprocess.run([sys.executable, __file__, "--memory-child", kind, str(path)],
                                    capture_output=True, text=True, check=True)
            runs[kind] = json.loads(result.stdout.splitlines()[-1])
        h, w = runs["headless"], runs["window"]
        print(f"memory: replay of {w['samples']} samples as fast as possible ({w['seconds']:.0f} s): RSS growth headless "
              f"{h['growth_mb']:.0f} MB (session tables {h['tables_mb']:.0f} MB), into the window on 'whole session' "
              f"{w['growth_mb']:.0f} MB; the UI's share {w['growth_mb'] - h['growth_mb']:.0f} MB (plot buffers {w['buffers_mb']:.0f} MB)")


def memory_child(kind: str, path: str) -> None:
    app = QtWidgets.QApplication(sys.argv[:1])  # noqa: F841 (alive while the window lives)
    recording = open_recording(path)
    window = None
    if kind == "window":
        settings = QtCore.QSettings(str(Path(path).with_suffix(".ini")), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(settings, Sessions())
        window.resize(1280, 800)
        window.show()
        window.live_view.window_box.setCurrentText("whole session")
        wait(0.5)
    before = rss_mb()
    t0 = time.monotonic()
    session = replay_session(ReplaySource(recording, None)).start()
    if window is not None:
        window._adopt(session)
        session.source.speed = None  # the transport set its 1x: as fast as possible instead
    while session.running:
        wait(0.5)
    wait(0.5)
    print(json.dumps({
        "growth_mb": rss_mb() - before, "tables_mb": table_mb(session.view), "samples": len(session.view.imu),
        "seconds": time.monotonic() - t0,
        "buffers_mb": sum(s.nbytes() for s in window.live_view.series.values()) / 1e6 if window else 0.0,
    }))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--live-seconds", type=float, default=60.0)
    parser.add_argument("--hours", type=float, default=2.0)
    parser.add_argument("--skip-redraw", action="store_true")
    parser.add_argument("--skip-live", action="store_true")
    parser.add_argument("--skip-memory", action="store_true")
    parser.add_argument("--memory-child", nargs=2, metavar=("KIND", "RECORDING"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.memory_child:
        memory_child(*args.memory_child)
        return
    app = QtWidgets.QApplication(sys.argv[:1])
    print(f"{os.cpu_count()} cores, Python {sys.version.split()[0]}, Qt platform {app.platformName()}")
    if not args.skip_redraw:
        bench_redraw()
    if not args.skip_live:
        bench_live(args.live_seconds)
    if not args.skip_memory:
        bench_memory(args.hours)


if __name__ == "__main__":
    main()

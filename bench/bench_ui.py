"""UI figures (offscreen Qt, software rendering): redraw cost, live CPU, memory over a long replay.

    python bench/bench_ui.py [--live-seconds S] [--hours H] [--skip-memory]

1. Redraw: the attitude plots (4 curves: AHF and onboard pitch and roll) over a 60 s and a 10 min
   window of 100 Hz data from the simulator; per frame: ``setData`` of every curve, the x range,
   and a synchronous repaint of a 1000x700 widget. Median ms per frame with peak downsampling (as
   the app) and plain, and the frames/s that leaves.
2. Live: the main window on the simulated bridge for S s (default 60): whole-process CPU % (reader,
   pipeline with ahf+hf+ecf, recorder, UI), UI frames/s drawn, median ms per redraw tick.
3. Memory: an H-hour (default 2) simulated flight, recorded as the app records (ahf, hf, ecf), is
   replayed as fast as possible into the window on its "whole session" window; RSS growth minus the
   session's own tables is what the UI costs.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6 import QtCore, QtWidgets  # noqa: E402

from groundstation.recording import open_recording  # noqa: E402
from groundstation.session.pipeline import Pipeline  # noqa: E402
from groundstation.sim.stream import Scenario, SimStream  # noqa: E402
from groundstation.ui import sessions  # noqa: E402
from groundstation.ui.live_view import attitude_plots  # noqa: E402
from groundstation.ui.main_window import MainWindow  # noqa: E402
from groundstation.ui.plots import StackedPlots  # noqa: E402
from groundstation.ui.series import Series, imu_quantities, onboard_quantities  # noqa: E402

FRAMES = 60


def rss_mb() -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024


def table_mb(pipeline: Pipeline) -> float:
    tables = [pipeline.imu, pipeline.onboard, pipeline.link.per_second, *pipeline.tables.values()]
    return sum(len(t) * len(t.columns) * 8 for t in tables) / 1e6


def simulated_series(seconds: float) -> dict[str, Series]:
    pipeline = Pipeline(("ahf",))
    stream = SimStream(Scenario("flight", seconds + 5, seed=1))
    for chunk in stream.advance(seconds + 1.5):
        pipeline.feed(int(chunk.t_s * 1e9), chunk.data)
    series = {"imu": Series(pipeline.imu, imu_quantities(pipeline.filters)), "onboard": Series(pipeline.onboard, onboard_quantities)}
    for s in series.values():
        s.take(threading.Lock())
    return series


def bench_redraw() -> None:
    series = simulated_series(610.0)
    plots = StackedPlots(attitude_plots(("ahf",)))
    plots.resize(1000, 700)
    plots.show()
    for window_s in (60.0, 600.0):
        for mode in ("peak", None):
            for item in plots.items:
                item.setDownsampling(auto=mode is not None, mode=mode or "peak", ds=1)
            times = []
            for _ in range(FRAMES):
                t0 = time.perf_counter()
                plots.draw(series, window_s, None)
                plots.repaint()
                times.append(time.perf_counter() - t0)
            ms = 1e3 * statistics.median(times)
            points = series["imu"].window(window_s).stop - series["imu"].window(window_s).start
            print(f"redraw 4 curves x {points:6d} points ({window_s:4.0f} s window), "
                  f"{'peak downsampling' if mode else 'plain            '}: {ms:5.1f} ms/frame  ({1e3 / ms:4.0f} frames/s possible)")
    plots.close()


def bench_live(app: QtWidgets.QApplication, seconds: float) -> None:
    with tempfile.TemporaryDirectory() as folder:
        settings = QtCore.QSettings(str(Path(folder) / "settings.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(settings, recordings_dir=Path(folder))
        window.resize(1280, 800)
        window.show()
        window.start_demo()
        tick_times = []
        tick = window.tick

        def timed_tick():
            t0 = time.perf_counter()
            tick()
            tick_times.append(time.perf_counter() - t0)

        window.timer.timeout.disconnect()
        window.timer.timeout.connect(timed_tick)
        wait(app, 2.0)  # past the simulated board's boot second
        tick_times.clear()
        cpu0, wall0, frames0 = time.process_time(), time.monotonic(), window.live_view.frames_drawn
        wait(app, seconds)
        cpu, wall = time.process_time() - cpu0, time.monotonic() - wall0
        frames = window.live_view.frames_drawn - frames0
        window.close()
    print(f"live 100 Hz on the simulated bridge, {wall:.0f} s: CPU {100 * cpu / wall:.1f} % of one core (whole process), "
          f"{frames / wall:.1f} UI frames/s, redraw tick median {1e3 * statistics.median(tick_times):.1f} ms "
          f"(p95 {1e3 * sorted(tick_times)[int(0.95 * len(tick_times))]:.1f} ms; the paint follows outside the tick)")


def wait(app: QtWidgets.QApplication, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 50)
        time.sleep(0.005)


def make_recording(path: Path, hours: float) -> None:
    from groundstation.recording import RecordingWriter

    duration_s = hours * 3600
    stream = SimStream(Scenario("flight", duration_s, seed=2))
    with RecordingWriter(path, {"source": "bench_ui", "filters": list(sessions.LIVE_FILTERS)}) as writer:
        t = 0.0
        while t < duration_s:
            t += 60.0
            for chunk in stream.advance(t):
                writer.write_chunk(int(chunk.t_s * 1e9), chunk.data)


def bench_memory(app: QtWidgets.QApplication, hours: float) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "long.gsrec"
        t0 = time.monotonic()
        make_recording(path, hours)
        print(f"memory: simulated a {hours:g} h recording ({path.stat().st_size / 1e6:.0f} MB) in {time.monotonic() - t0:.0f} s")
        settings = QtCore.QSettings(str(Path(folder) / "settings.ini"), QtCore.QSettings.Format.IniFormat)
        window = MainWindow(settings)
        window.resize(1280, 800)
        window.show()
        window.live_view.window_box.setCurrentText("whole session")
        wait(app, 0.5)
        before = rss_mb()
        session = sessions.replay_session(open_recording(path), None).start()
        window._adopt(session)
        session.source.speed = None  # the transport set its 1x: as fast as possible instead
        t0 = time.monotonic()
        while session.running:
            wait(app, 1.0)
        wait(app, 0.5)
        elapsed = time.monotonic() - t0
        growth = rss_mb() - before
        own = table_mb(session.pipeline)
        buffers = sum(s.time_s.nbytes + sum(v.nbytes for v in s.values.values()) for s in window.live_view.series.values()) / 1e6
        recording_mb = path.stat().st_size / 1e6  # the replay source holds the file in memory
        print(f"memory: replayed {len(session.pipeline.imu)} samples in {elapsed:.0f} s into the window: RSS +{growth:.0f} MB; "
              f"session tables {own:.0f} MB, recording bytes {recording_mb:.0f} MB; UI beyond them "
              f"{growth - own - recording_mb:.0f} MB (plot buffers {buffers:.0f} MB)")
        window.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--live-seconds", type=float, default=60.0)
    parser.add_argument("--hours", type=float, default=2.0)
    parser.add_argument("--skip-memory", action="store_true")
    args = parser.parse_args()
    app = QtWidgets.QApplication(sys.argv[:1])
    print(f"{os.cpu_count()} cores, Python {sys.version.split()[0]}, Qt platform {app.platformName()}")
    bench_redraw()
    bench_live(app, args.live_seconds)
    if not args.skip_memory:
        bench_memory(app, args.hours)


if __name__ == "__main__":
    main()

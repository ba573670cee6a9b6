"""Seeking in the app's replay: the computed session revealed up to a clock against the re-feed from the start.

    QT_QPA_PLATFORM=offscreen python bench/bench_reveal.py [--minutes 10 60] [--filters ahf,hf,ecf]

For each length, a simulated flight (100 Hz, raw) is recorded with ``--filters`` as its estimators. Then:

- baseline, as the window seeked before (``ReplaySeek``, deleted): every chunk before minute 0.9 x length
  fed through a fresh pipeline;
- open: ``load_session`` once (what the window's worker runs; its progress bar meanwhile);
- seek: in a real ``MainWindow`` (offscreen), on the "whole session" window, the time from ``seek(t)``
  to the plots drawn at ``t`` (the seek, then one redraw tick), forward to 90 %, back to 10 %, to
  50 %; and the same on the 30 s window. Medians of ``--repeats``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from bench_session import make_recording  # noqa: E402 (bench/ is on the path)
from timing import median_seconds  # noqa: E402

from PySide6 import QtCore, QtWidgets  # noqa: E402

from groundstation.recording import RecordingWriter, open_recording  # noqa: E402
from groundstation.session_makers.load import load_session  # noqa: E402
from groundstation.session_makers.replay import pipeline_for  # noqa: E402
from groundstation.session.playback import RevealSession  # noqa: E402
from groundstation.session_makers.factory import Sessions
from groundstation.ui.main_window import MainWindow  # noqa: E402


def with_filters(path: Path, filters: tuple[str, ...], out: Path) -> None:
    """``path``'s chunks in a recording whose header names ``filters`` (what the app would have recorded)."""
    recording = open_recording(path)
    with RecordingWriter(out, {"source": "bench", "filters": list(filters)}) as writer:
        for t_host_ns, data in recording.chunks():
            writer.write_chunk(t_host_ns, data)


def refeed_seconds(path: Path, t_s: float) -> float:
    """What a seek to ``t_s`` cost before: every chunk before it through a fresh pipeline."""
    recording = open_recording(path)
    t0 = time.perf_counter()
    pipeline = pipeline_for(recording)
    t0_ns = int(recording.chunk_t_host_ns[0])
    for t_host_ns, data in recording.chunks():
        if t_host_ns - t0_ns >= t_s * 1e9:
            break
        pipeline.feed(t_host_ns, data)
    return time.perf_counter() - t0


def seek_seconds(window: MainWindow, t_s: float) -> float:
    t0 = time.perf_counter()
    window.seek(t_s)
    window.tick()  # the redraw that shows it
    return time.perf_counter() - t0


def bench(minutes: float, filters: tuple[str, ...], repeats: int, window: MainWindow) -> None:
    with tempfile.TemporaryDirectory() as folder:
        raw, path = Path(folder) / "raw.gsrec", Path(folder) / "flight.gsrec"
        make_recording(raw, minutes / 60)
        with_filters(raw, filters, path)
        duration_s = minutes * 60
        print(f"\n{minutes:g} min recording ({path.stat().st_size / 1e6:.0f} MB), estimators {', '.join(filters)}")
        baseline = refeed_seconds(path, 0.9 * duration_s)
        print(f"  baseline: seek to {0.9 * duration_s / 60:.1f} min by re-feeding from the start: {baseline:.2f} s")
        t0 = time.perf_counter()
        data = load_session(path)
        opened = time.perf_counter() - t0
        print(f"  open (load_session, once; the worker's job): {opened:.2f} s ({len(data)} IMU rows)")
        session = RevealSession(data, path, paused=True)
        window._adopt(session)
        for name in ("whole session", "30 s"):
            window.live_view.window_box.setCurrentText(name)
            times = {}
            for label, fraction in (("forward to 90 %", 0.9), ("back to 10 %", 0.1), ("to 50 %", 0.5)):
                def seek(fraction=fraction):
                    seek_seconds(window, 0.0)
                    return seek_seconds(window, fraction * duration_s)
                times[label] = median_seconds(seek, repeats)  # includes the seek to 0 and its redraw
            figures = ", ".join(f"{label} {seconds * 1e3:.0f} ms" for label, seconds in times.items())
            worst = max(times.values())
            print(f"  seek + redraw on the '{name}' window (with a seek to 0 before each): {figures}; "
                  f"worst {worst * 1e3:.0f} ms = 1/{baseline / worst:.0f} of the baseline")
        window.disconnect()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, nargs="+", default=[10.0, 60.0])
    parser.add_argument("--filters", default="ahf,hf,ecf")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    app = QtWidgets.QApplication(sys.argv[:1])  # noqa: F841 (alive while the window lives)
    settings = QtCore.QSettings(str(Path(tempfile.mkdtemp()) / "bench.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings, Sessions())
    window.resize(1280, 800)
    window.show()
    window.timer.stop()  # the bench ticks it itself
    print(f"Qt platform {app.platformName()}, Python {sys.version.split()[0]}")
    for minutes in args.minutes:
        bench(minutes, tuple(args.filters.split(",")), args.repeats, window)


if __name__ == "__main__":
    main()

"""The app's start (issue 25): the window paints before numba and the estimators' kernels load, and the
simulated bridge's data follows once its session's estimators exist (on a machine's first start, while
their kernels compile: tests/ui/test_first_start.py). A real ``groundstation app --demo`` process, Qt
offscreen, stopped by its own first-frame stopwatch (``ui/first_frame.py``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from groundstation.estimation import live_estimators
from groundstation.session_makers.load import load_session
from tests.waiting import LIMIT_MS

ROOT = Path(__file__).resolve().parents[2]


def start_app(tmp_path: Path) -> list[str]:
    """stdout and stderr of ``python -X importtime -m groundstation app --demo`` in one stream, in order:
    the imports (stderr, unbuffered) and the stopwatch's moments (flushed) as they happened."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "QT_QPA_PLATFORM": "offscreen", "GROUNDSTATION_FIRST_FRAME": "1",
           "XDG_CONFIG_HOME": str(tmp_path / "config"), "GROUNDSTATION_RECORDINGS": str(tmp_path / "recordings")}
    done = subprocess.run([sys.executable, "-X", "importtime", "-m", "groundstation", "app", "--demo"], env=env, cwd=tmp_path,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)
    assert done.returncode == 0, done.stdout[-2000:]
    return done.stdout.splitlines()


def position(lines: list[str], predicate) -> int:
    return next(i for i, line in enumerate(lines) if predicate(line))


def test_the_window_paints_before_numba_loads_and_the_data_follows(tmp_path):
    lines = start_app(tmp_path)
    paint = position(lines, lambda line: line.startswith("first paint "))
    data = position(lines, lambda line: line.startswith("first data "))
    numba = position(lines, lambda line: line.startswith("import time:") and line.split("|")[-1].strip() == "numba")  # at any depth
    kernels = position(lines, lambda line: line.rstrip().endswith("groundstation.estimation.base"))  # the kernels' module
    assert paint < numba < data and paint < kernels < data
    paint_s, data_s = (float(lines[i].split()[-1]) for i in (paint, data))
    assert 0 < paint_s <= data_s
    # The source opened once its estimators existed: the recording, replayed, has every live estimator's
    # attitude on every sample, from the first.
    (recording,) = (tmp_path / "recordings").glob("*.gsrec")
    data = load_session(recording)
    assert len(data) > 0 and data.estimated == live_estimators()
    assert all(np.isfinite(data.quaternion(name)).all() for name in data.estimated)


def test_the_first_paint_comes_before_scipy_pandas_pyarrow_and_openpyxl(tmp_path):
    lines = start_app(tmp_path)
    paint = position(lines, lambda line: line.startswith("first paint "))
    before = {line.split("|")[-1].strip() for line in lines[:paint] if line.startswith("import time:")}
    assert not before & {"numba", "scipy", "pandas", "pyarrow", "openpyxl"}


def test_the_tabs_out_of_sight_are_built_when_first_asked_for_with_their_titles_and_visibility(window, qtbot):
    """The window shows before the tabs behind Attitude are built; the first session (or a click) builds
    them in their places, the heading and position tabs still hidden until their data, the current tab kept."""
    view = window.live_view
    tabs = view.tabs
    titles = [tabs.tabText(i) for i in range(tabs.count())]
    assert titles == ["Attitude", "Sensors", "AHF diagnostics", "Heading", "Position", "Flight", "Channels", "Vibration"]
    assert not {"sensors", "diagnostics", "heading", "position", "flight", "vibration"} & view.__dict__.keys()
    assert [tabs.isTabVisible(i) for i in range(tabs.count())] == [True, True, True, False, False, False, True, True]
    tabs.setCurrentIndex(titles.index("Vibration"))  # a click on a tab not built: built, and shown
    assert "vibration" in view.__dict__ and tabs.currentWidget() is view.vibration
    tabs.setCurrentIndex(titles.index("Channels"))
    window.start_demo()
    qtbot.waitUntil(lambda: len(window.session.view.imu) > 50, timeout=LIMIT_MS)
    assert [tabs.tabText(i) for i in range(tabs.count())] == titles
    assert [tabs.widget(i) for i in range(tabs.count())] == [view.attitude, view.sensors, view.diagnostics, view.heading,
                                                             view.position, view.flight, view.channels, view.vibration]
    assert tabs.currentWidget() is view.channels
    tabs.setCurrentWidget(view.sensors)  # a built tab shows the session's samples
    qtbot.waitUntil(lambda: view.frames_drawn > 3 and view.current_plots() is view.sensors, timeout=LIMIT_MS)

"""The app's first start on a machine (issue 34): numba's cache empty, as after an install. The window
shows the simulated bridge's data, or a file's, while another process compiles the estimators' kernels
(counted in the status bar, marked in the Estimators panel), a file's estimators join when compiled, and
Ctrl-C during that compile closes it at once with the recording closed. Real ``groundstation app``
processes, Qt offscreen, each with a cache folder of its own."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np

from groundstation.estimation import live_estimators
from groundstation.recording import open_recording
from groundstation.session.playback import RevealSession
from groundstation.session_makers.load import load_session
from groundstation.stopwatch import UNCOMPILED
from tests.session.test_first_start import ROOT, Lines, compiled_kernels, first_start_env, posix_only, processes_with
from tests.waiting import LIMIT_MS, LIMIT_S, wait_for

SAMPLE = ROOT / "recordings" / "samples" / "flight-both-lossy.gsrec"  # 30 s; its live session ran AHF only


def test_the_first_start_shows_data_while_the_kernels_compile(tmp_path):
    """The stopwatch closes the window at the first data, which came while the kernels were compiling; the
    recording, replayed, has every estimator on every sample from the first."""
    env = {**first_start_env(tmp_path), "QT_QPA_PLATFORM": "offscreen"}
    done = subprocess.run([sys.executable, "-m", "groundstation", "app", "--demo"], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    (line,) = [line for line in done.stdout.splitlines() if line.startswith(UNCOMPILED)]
    assert {"ahf2", "ukf", "sssrukf"} <= set(line.removeprefix(UNCOMPILED).strip().split(","))
    (recording,) = (tmp_path / "recordings").glob("*.gsrec")
    data = load_session(recording)
    assert len(data) > 0 and data.estimated == live_estimators()
    assert all(np.isfinite(data.quaternion(name)).all() for name in data.estimated)


@posix_only
def test_ctrl_c_during_the_first_compile_closes_the_window_and_the_recording(tmp_path):
    env = {**first_start_env(tmp_path), "QT_QPA_PLATFORM": "offscreen"}
    del env["GROUNDSTATION_FIRST_FRAME"]  # the window stays open: Ctrl-C closes it
    app = subprocess.Popen([sys.executable, "-m", "groundstation", "app", "--demo"], env=env, cwd=tmp_path,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        Lines(app)
        recordings = tmp_path / "recordings"
        wait_for(lambda: any(path.stat().st_size > 20_000 for path in recordings.glob("*.gsrec")) or app.poll() is not None,
                 what="the demo recorded")
        assert app.poll() is None, app.stderr.read()
        assert not compiled_kernels(tmp_path / "numba", "ukf")  # still compiling (ukf's kernel comes last)
        app.send_signal(signal.SIGINT)
        app.wait(timeout=LIMIT_S)
    finally:
        if app.poll() is None:
            app.kill()
    stderr = app.stderr.read()
    assert app.returncode == 0 and "Traceback" not in stderr, stderr[-2000:]
    wait_for(lambda: not processes_with(str(tmp_path / "numba")), what="the compiling process gone with the app")
    (path,) = recordings.glob("*.gsrec")
    recording = open_recording(path)
    assert recording.closed_cleanly and not recording.damage


def test_a_file_opened_on_a_first_start_shows_at_once_and_its_estimator_joins_when_compiled(tmp_path):
    """``app FILE`` with numba's cache empty: the recording (it ran AHF) shows before AHF's kernel is compiled,
    computed without it, while another process compiles it; then the window computes it again with AHF (the
    stopwatch's "every estimator", once the view lacks none) and closes."""
    env = {**first_start_env(tmp_path), "QT_QPA_PLATFORM": "offscreen"}
    done = subprocess.run([sys.executable, "-m", "groundstation", "app", str(SAMPLE)], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert [line.removeprefix(UNCOMPILED).strip() for line in lines if line.startswith(UNCOMPILED)] == ["ahf"]
    assert [line.split()[0] for line in lines if line[0].isalpha()][-1:] == ["every"]  # "every estimator <CPU s>", last
    assert compiled_kernels(tmp_path / "numba", "ahf")


def test_estimators_compiling_are_counted_in_the_status_bar_and_marked_in_the_panel(window, qtbot):
    """A file computed without the estimators whose kernels compile (as ``Loading`` leaves them out on a
    first start): the status bar says how many, their "show" boxes say so and cannot be asked for; a session
    that lacks none says nothing."""
    data = load_session(SAMPLE, filters=("ahf", "hf"))
    window._adopt(RevealSession(data, SAMPLE, uncompiled=("ukf", "sssrukf")))
    qtbot.waitUntil(lambda: window.compiling_label.isVisible(), timeout=LIMIT_MS)
    assert window.compiling_label.text() == "compiling estimators: 2 left"
    panel = window.estimator_panel
    assert panel.shown["ukf"].text() == "UKF …" and "compiling" in panel.shown["ukf"].toolTip()
    assert not panel.shown["ukf"].isEnabled()
    assert panel.shown["ecf"].text() == "ECF" and panel.shown["ecf"].isEnabled()
    window._adopt(RevealSession(data, SAMPLE))
    qtbot.waitUntil(lambda: not window.compiling_label.isVisible(), timeout=LIMIT_MS)
    assert panel.shown["ukf"].text() == "UKF" and panel.shown["ukf"].isEnabled()

"""The app's first start on a machine (issue 34): numba's cache empty, as after an install. The window
shows the simulated bridge's data while another process compiles the estimators' kernels, and Ctrl-C
during that compile closes it at once with the recording closed. Real ``groundstation app --demo``
processes, Qt offscreen, each with a cache folder of its own."""

from __future__ import annotations

import signal
import subprocess
import sys

import numpy as np

from groundstation.estimation import live_estimators
from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from groundstation.stopwatch import UNCOMPILED
from tests.session.test_first_start import Lines, compiled_kernels, first_start_env, posix_only, processes_with
from tests.waiting import LIMIT_S, wait_for


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

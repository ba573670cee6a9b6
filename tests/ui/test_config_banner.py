"""A live session whose link says other full scales without a device restart (a forged CONFIG at 4 s in a
±4 g hover, replayed through the live path): the window shows the warning banner, the data keeps ±4 g,
and the user's button decides."""

import threading

import numpy as np
import pytest
from PySide6 import QtCore

from groundstation.recording import open_recording
from groundstation.session_makers.factory import replay_session
from groundstation.sources import ReplaySource
from tests.crafted_files import forged_config_recording
from tests.waiting import LIMIT_MS

FORGED_AT_S = 2.0


@pytest.fixture(scope="module")
def forged(tmp_path_factory):
    return forged_config_recording(tmp_path_factory.mktemp("forged"), at_s=FORGED_AT_S, duration_s=6.0, accel_fs_g=16)


class HeldFrom:
    """A replay that holds its chunks from ``t_s`` (recorded time) until ``release`` is set, as a link goes
    quiet: the user's answer comes before the rest of the flight however long a loaded machine takes to
    show the banner (at 2x the 6 s flight ended 2 s after the forged CONFIG, and with it the rows that
    show the answer's scales)."""

    def __init__(self, source: ReplaySource, t_s: float):
        self._source = source
        self._from_ns = int(source.recording.chunk_t_host_ns[0]) + round(t_s * 1e9)
        self._pending = None
        self.release = threading.Event()

    def __getattr__(self, name):
        return getattr(self._source, name)

    def read(self):
        chunk = self._pending or self._source.read()
        if chunk is not None and chunk.t_host_ns >= self._from_ns and not self.release.wait(0.05):
            self._pending = chunk
            return None
        self._pending = None
        return chunk


def newest_acc_norm_g(session) -> float:
    with session.lock:
        rows = session.pipeline.imu.tail(20)
    columns = session.pipeline.imu.columns
    acc = rows[:, [columns.index(f"acc_{a}_g") for a in "xyz"]]
    return float(np.median(np.linalg.norm(acc, axis=1)))


@pytest.mark.parametrize("accept, norm_g", [(False, 1.0), (True, 4.0)])
def test_the_banner_holds_the_scales_until_the_user_decides(window, qtbot, forged, accept, norm_g):
    source = HeldFrom(ReplaySource(open_recording(forged), speed=2), FORGED_AT_S + 0.5)
    window._start(str(forged), lambda: replay_session(source).start())
    session = window.session
    qtbot.waitUntil(window.config_banner.isVisible, timeout=LIMIT_MS)
    text = window.config_banner.label.text()
    assert "WITHOUT A RESTART" in text and "±4 g → ±16 g" in text
    assert newest_acc_norm_g(session) == pytest.approx(1.0, abs=0.1)  # held: still ±4 g
    button = window.config_banner.accept_button if accept else window.config_banner.keep_button
    qtbot.mouseClick(button, QtCore.Qt.MouseButton.LeftButton)
    assert not window.config_banner.isVisible()
    kind = "config_accepted" if accept else "config_kept"
    assert any(e["kind"] == kind for e in session.pipeline.events)
    count = len(session.pipeline.imu)
    source.release.set()
    qtbot.waitUntil(lambda: len(session.pipeline.imu) > count + 40, timeout=LIMIT_MS)
    assert newest_acc_norm_g(session) == pytest.approx(norm_g, abs=0.2 * norm_g)

"""A live session whose link says other full scales without a device restart (a forged CONFIG at 4 s in a
±4 g hover, replayed through the live path): the window shows the warning banner, the data keeps ±4 g,
and the user's button decides."""

import numpy as np
import pytest
from PySide6 import QtCore

from groundstation.session.factory import open_session
from tests.crafted_files import forged_config_recording


@pytest.fixture(scope="module")
def forged(tmp_path_factory):
    return forged_config_recording(tmp_path_factory.mktemp("forged"), at_s=2.0, duration_s=6.0, accel_fs_g=16)


def newest_acc_norm_g(session) -> float:
    with session.lock:
        rows = session.pipeline.imu.tail(20)
    columns = session.pipeline.imu.columns
    acc = rows[:, [columns.index(f"acc_{a}_g") for a in "xyz"]]
    return float(np.median(np.linalg.norm(acc, axis=1)))


@pytest.mark.parametrize("accept, norm_g", [(False, 1.0), (True, 4.0)])
def test_the_banner_holds_the_scales_until_the_user_decides(window, qtbot, forged, accept, norm_g):
    window._start(f"{forged}?speed=2", lambda: open_session(f"{forged}?speed=2").start())
    session = window.session
    qtbot.waitUntil(window.config_banner.isVisible, timeout=20_000)
    text = window.config_banner.label.text()
    assert "WITHOUT A RESTART" in text and "±4 g → ±16 g" in text
    assert newest_acc_norm_g(session) == pytest.approx(1.0, abs=0.1)  # held: still ±4 g
    button = window.config_banner.accept_button if accept else window.config_banner.keep_button
    qtbot.mouseClick(button, QtCore.Qt.MouseButton.LeftButton)
    assert not window.config_banner.isVisible()
    kind = "config_accepted" if accept else "config_kept"
    assert any(e["kind"] == kind for e in session.pipeline.events)
    count = len(session.pipeline.imu)
    qtbot.waitUntil(lambda: len(session.pipeline.imu) > count + 40, timeout=20_000)
    assert newest_acc_norm_g(session) == pytest.approx(norm_g, abs=0.2 * norm_g)

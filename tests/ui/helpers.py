"""Shared steps of the window tests."""

import pandas as pd

from tests.waiting import LIMIT_MS


def open_file(window, qtbot, path, timeout_ms: int = LIMIT_MS) -> None:
    """Open ``path`` as File > Open does and wait until it is computed (or refused, in the banner)."""
    window.open_recording(path)
    qtbot.waitUntil(lambda: window.loading is None, timeout=timeout_ms)


def play_to_the_end(window, qtbot, timeout_ms: int = LIMIT_MS) -> None:
    """Play the replay (paused or not) at 64x until the clock reaches the end of the data."""
    window.replay_bar.speed_box.setCurrentIndex(window.replay_bar.speed_box.findData(64.0))
    if window.session.source.paused:
        window.replay_bar.play_button.click()
    qtbot.waitUntil(lambda: not window.session.running, timeout=timeout_ms)


def export_csv(window, qtbot, panel, row, out):
    """The panel's Export… on the session of ``row``, to ``out`` (CSV)."""
    panel.tree.setCurrentItem(panel.tree.topLevelItem(row))
    dialog = panel.export_selected()
    assert dialog is not None, (row, window.banner.text(), [e.label for e in panel.entries])
    qtbot.addWidget(dialog)
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".csv"))
    dialog.path_edit.setText(str(out))
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text().startswith(f"wrote {out}"), dialog.status.text()
    return pd.read_csv(out)

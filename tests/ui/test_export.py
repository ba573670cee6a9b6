"""The export dialog writes the file it names, from a worker thread, with progress; Cancel leaves nothing."""

from pathlib import Path

import pandas as pd

from groundstation.session_makers.load import load_session
from groundstation.ui.export_dialog import ExportDialog

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_export_dialog_writes_the_selected_range(window, qtbot, recording, tmp_path):
    open_file(window, qtbot, recording)
    dialog = window.export()
    qtbot.addWidget(dialog)
    out = tmp_path / "flight.csv"
    dialog.path_edit.setText(str(out))
    dialog.t_from.setValue(5.0)
    dialog.t_to.setValue(10.0)
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text().startswith(f"wrote {out}") and dialog.progress.value() == 1000
    table = pd.read_csv(out)
    assert table["time_s"].min() >= 5.0 and table["time_s"].max() <= 10.0 and len(table) > 400
    assert {"ahf_pitch_deg", "ahf_roll_deg", "onboard_pitch_deg"} <= set(table.columns)


def test_export_dialog_writes_a_workbook(qtbot, recording, tmp_path):
    dialog = ExportDialog(load_session, recording, 30.0)
    qtbot.addWidget(dialog)
    assert dialog.format_box.currentData() == ".xlsx"  # the first choice
    out = tmp_path / "flight.xlsx"
    dialog.path_edit.setText(str(out))
    dialog.rate.setValue(10)
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text().startswith(f"wrote {out}: sheets Session, Attitude") and out.stat().st_size > 10_000


def test_cancel_leaves_no_file(qtbot, recording, tmp_path):
    dialog = ExportDialog(load_session, recording, 30.0)
    qtbot.addWidget(dialog)
    out = tmp_path / "cancelled.parquet"
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".parquet"))
    dialog.path_edit.setText(str(out))
    dialog.export_button.click()
    dialog.cancel_button.click()  # before the decoder's first progress report has passed
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text() == "cancelled; nothing was written"
    assert not out.exists() and not list(tmp_path.glob(".cancelled*"))


def test_the_dialog_saves_into_documents_then_where_the_user_last_exported(window, qtbot, recording, tmp_path, monkeypatch):
    """Not beside the recording in the app's hidden data folder (issue 24, defect 9)."""
    home = tmp_path / "home"
    (home / "Documents").mkdir(parents=True)
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.delenv("XDG_DOCUMENTS_DIR", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home / ".config"))  # no user-dirs.dirs: Documents is ~/Documents
    open_file(window, qtbot, recording)
    dialog = window.export()
    qtbot.addWidget(dialog)
    assert Path(dialog.path_edit.text()) == home / "Documents" / "flight.xlsx"
    elsewhere = tmp_path / "exports"
    elsewhere.mkdir()
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".csv"))
    dialog.path_edit.setText(str(elsewhere / "first.csv"))
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    dialog.close()
    again = window.export()
    qtbot.addWidget(again)
    assert Path(again.path_edit.text()).parent == elsewhere  # remembered, also across restarts (the settings)


def test_the_rate_box_is_off_for_a_format_that_keeps_every_row(qtbot, recording, tmp_path):
    """MCAP keeps every row of every table (``ExportFormat.every_row``): its rate box is disabled, and a rate set
    before it was chosen does not refuse the export."""
    dialog = ExportDialog(load_session, recording, 30.0)
    qtbot.addWidget(dialog)
    assert dialog.rate.isEnabled()
    dialog.rate.setValue(10)
    dialog.format_box.setCurrentIndex(dialog.format_box.findData(".mcap"))
    assert not dialog.rate.isEnabled()
    out = tmp_path / "flight.mcap"
    dialog.path_edit.setText(str(out))
    dialog.export_button.click()
    qtbot.waitUntil(lambda: dialog.job.done and not dialog.timer.isActive(), timeout=LIMIT_MS)
    assert dialog.status.text().startswith(f"wrote {out}") and out.stat().st_size > 10_000

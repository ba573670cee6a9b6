"""File > Flight report… in the real window: the open file's report written in the background, the
status bar saying where (until the next file: it stayed over that file's name); with nothing open, the banner
says why not."""

from PySide6 import QtWidgets

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS


def test_the_file_menu_writes_the_flight_report_and_says_where(window, qtbot, recording, tmp_path):
    open_file(window, qtbot, recording)
    file_menu = next(m for m in window.menuBar().findChildren(QtWidgets.QMenu) if m.title() == "&File")
    assert "Flight &report…" in [a.text() for a in file_menu.actions()]
    out = tmp_path / "flight-report.html"
    job = window.flight_report(out)
    qtbot.waitUntil(lambda: job.done, timeout=LIMIT_MS)
    qtbot.waitUntil(lambda: str(out) in window.statusBar().currentMessage(), timeout=LIMIT_MS)
    assert job.error is None and not window.banner.isVisible()
    text = out.read_text(encoding="utf-8")
    assert "<h2>Findings</h2>" in text and recording.name in text
    open_file(window, qtbot, recording)  # the next session: its own name in the status bar, not the last report
    assert window.statusBar().currentMessage() == "" and window.source_label.isVisible()


def test_with_nothing_open_the_banner_says_why(window, tmp_path):
    assert window.flight_report(tmp_path / "r.html") is None
    assert window.banner.isVisible() and "Nothing to report on" in window.banner.text()
    assert not (tmp_path / "r.html").exists()

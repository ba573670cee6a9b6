"""Names from data reach the terminal with their control characters shown, never acting (issue 37.8): a
file name that would set the window title, clear the screen or forge a progress line, and a log whose
warnings carry its names, are printed one line each with ``\\x1b``, ``\\n`` (``text.clean``, visible)."""

import shutil

from groundstation.cli import main
from tests.crafted_files import ulog_topics

EVIL = "evil\x1b]0;owned\x07\x1b[2J\n[9] fake.ulg: 12 estimators against the truth (0.1 s)\n"


def test_a_folder_runs_progress_shows_file_names_escaped(tmp_path, capsys):
    logs = tmp_path / "logs"
    logs.mkdir()
    ulog_topics(logs / "plain.ulg", [])
    shutil.copy(logs / "plain.ulg", logs / f"{EVIL}.ulg")
    (logs / f"cut{EVIL}.ulg").write_bytes(b"ULog\x01\x12\x35")  # unreadable: its error names it
    assert main(["evaluate", str(logs), "--out", str(tmp_path / "out"), "--filters", "ahf2", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out
    lines = out.splitlines()
    assert len(lines) == 4 and sum(line.startswith("[") for line in lines) == 3  # three logs, then the summary
    assert any(line.startswith("[") and "evil\\x1b]0;owned\\x07\\x1b[2J\\n[9] fake.ulg" in line for line in lines)


def test_an_error_and_the_warnings_are_one_line_each(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path / EVIL)]) == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and len(err.splitlines()) == 1 and "evil\\x1b]0;owned" in err
    log = tmp_path / "case.ulg"
    ulog_topics(log, ["Evil\x1b]0;owned\x07forged", "evil\x1b]0;owned\x07forged"])  # kept apart: a warning naming both
    assert main(["evaluate", str(log), "--filters", "ahf2"]) == 0
    out = capsys.readouterr().out
    warnings = [line for line in out.splitlines() if line.startswith("warning:")]
    assert "\x1b" not in out and len(warnings) == 1 and "forged" in warnings[0]

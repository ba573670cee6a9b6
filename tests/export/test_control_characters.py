"""Text is text (issue 31.5): a PX4 log's ANSI-coloured messages, NUL and BEL in its messages, ESC in an
ArduPilot MSG, and a topic whose name carries an escape sequence never end an export nor reach a file as
control characters: workbook, CSV header, MCAP log messages and the HTML report read clean (``text.clean``).
The logs are crafted here (tests/crafted_files.py); pyulog and DFReader read the same texts raw."""

import re

import pandas as pd
import pytest
from openpyxl import load_workbook
from pymavlink import DFReader
from pyulog import ULog

from groundstation.cli import main
from groundstation.text import clean
from tests.crafted_files import dataflash_types, ulog_topics
from tests.export.test_mcap import read_mcap

READY = "[commander] \x1b[32mReady for takeoff!\x1b[0m"
PX4_SAID = [(5_100_000, 6, READY), (5_200_000, 4, "bell\x07 and nul\x00 here"), (5_300_000, 3, "\x1b]0;owned\x07title set")]
ARDUPILOT_SAID = ["esc \x1b[31mred\x1b[0m done", "clear \x1b[2J\x1b[H screen"]
EVIL_TOPIC = "evil\x1b[2Jtopic"
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f]")


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("said")
    ulog_topics(folder / "px4.ulg", [EVIL_TOPIC], PX4_SAID)
    dataflash_types(folder / "ardupilot.bin", [], ARDUPILOT_SAID)
    return folder


def said_raw(path):
    """The texts as the independent readers give them: pyulog's logged messages, DFReader's MSG."""
    if path.suffix == ".ulg":
        return [m.message for m in ULog(str(path)).logged_messages]
    reader, out = DFReader.DFReader_binary(str(path), zero_time_base=False), []
    while (msg := reader.recv_match(type="MSG")) is not None:
        out.append(msg.Message)
    return out


def test_clean_text_and_visible_names():
    assert clean(READY) == "[commander] Ready for takeoff!"
    assert clean("a\tb\nc\x00\x07\x7f\x9b31md\r") == "a\tb\ncd"
    assert clean("\x1b]0;owned\x07title") == "title"  # a window title set: gone whole
    assert clean("bytes \udcff of a file name") == "bytes  of a file name"  # a lone surrogate cannot be UTF-8
    assert clean("ümlaut, 中文, emoji 🛩 stay") == "ümlaut, 中文, emoji 🛩 stay"
    assert clean("name\x1b[2J\nfake line", visible=True) == "name\\x1b[2J\\nfake line"
    assert clean("tab\tand \udcff", visible=True) == "tab\\tand \\udcff"


@pytest.mark.parametrize("name", ["px4.ulg", "ardupilot.bin"])
def test_the_workbook_holds_the_messages_clean(logs, tmp_path, name):
    raw = said_raw(logs / name)
    assert any(CONTROL.search(text) for text in raw)  # the crafted texts are as hostile as meant
    out = tmp_path / "said.xlsx"
    assert main(["export", str(logs / name), "--out", str(out), "--filters", "ahf2"]) == 0
    texts = [c for row in load_workbook(out, read_only=True)["Session"].iter_rows(values_only=True) for c in row if isinstance(c, str)]
    assert not any(CONTROL.search(t) for t in texts)
    for text in raw:
        assert clean(text) in texts
    if name == "px4.ulg":
        assert "[commander] Ready for takeoff!" in texts


def test_csv_header_and_mcap_messages_clean(logs, tmp_path):
    csv = tmp_path / "px4.csv"
    assert main(["export", str(logs / "px4.ulg"), "--out", str(csv), "--filters", "ahf2"]) == 0
    header = csv.read_text().splitlines()[0]
    assert not CONTROL.search(header) and "evil\\x1b[2jtopic_value" in header.split(",")
    assert pd.read_csv(csv)["evil\\x1b[2jtopic_value"].count() == 10
    for name in ("px4.ulg", "ardupilot.bin"):
        mcap = tmp_path / f"{name}.mcap"
        assert main(["export", str(logs / name), "--out", str(mcap), "--filters", "ahf2"]) == 0
        messages = [log.message for _, log in read_mcap(mcap)["/events"]]
        assert not any(CONTROL.search(m) for m in messages)
        assert all(clean(text) in messages for text in said_raw(logs / name))


def test_the_report_holds_the_messages_clean(logs, tmp_path):
    for name in ("px4.ulg", "ardupilot.bin"):
        page = tmp_path / f"{name}.html"
        assert main(["report", str(logs / name), "--out", str(page), "--filters", "ahf2"]) == 0
        assert not CONTROL.search(page.read_text())

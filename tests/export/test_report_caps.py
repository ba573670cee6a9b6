"""A log that says the same thing thousands of times gives a report of bounded size (issue 37: one with
60,000 warnings gave 60,001 findings, 13.7 MB): its findings are listed up to a cap, the rest counted, as
its events are."""

import re
import sys
from pathlib import Path

import numpy as np
from pymavlink import DFReader

from groundstation.export.report import MAX_EVENTS, MAX_FINDINGS, write_report
from groundstation.session_makers.load import load_session

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "autopilot"))
from mavlink_helpers import write_dataflash  # noqa: E402

ERRORS = 6_000  # as many as 60,000 cost the test 17 s; the cap is the same


def test_thousands_of_autopilot_errors_give_a_bounded_report(tmp_path):
    """An ArduPilot log whose ERR record says 'error 1' ERRORS times (each a high finding), 6 s of ATT."""
    t_att_us = 1_000_000 + 20_000 * np.arange(300)
    t_err_us = 1_000_000 + 100 * np.arange(ERRORS)
    log = tmp_path / "chatty.bin"
    write_dataflash(log, {
        "ATT": ("Qfff", "TimeUS,Roll,Pitch,Yaw", [(int(t), 1.0, 2.0, 3.0) for t in t_att_us]),
        "ERR": ("QBB", "TimeUS,Subsys,ECode", [(int(t), 2, 1) for t in t_err_us]),
    })
    reader = DFReader.DFReader_binary(str(log))  # the oracle: pymavlink reads as many ERR records
    assert reader.counts[reader.name_to_id["ERR"]] == ERRORS
    page = write_report(load_session(log, exact=True), tmp_path / "chatty.html", "chatty.bin").read_text()
    listed = len(re.findall(r'<li class="finding ', page))
    assert listed == MAX_FINDINGS
    more = re.search(r"… and (\d+) more findings", page)
    assert more and listed + int(more.group(1)) >= ERRORS  # every error counted: listed or in the rest
    assert f"… and {ERRORS - MAX_EVENTS} more events" in page
    assert len(page) < 300_000

"""One figure, computed once: a log's IMU rate, link loss and duration are the same number in the window
(the functions its attitude title and link panel call, on the played-back session), the flight report,
the logbook's dataset, the CLI's totals and the workbook's Session sheet; and the right number, by
pymavlink's own reading: ``ardusub_rov_surface.tlog`` (cut to its start) with three frames injected under
the vehicle's ids loses no frame (its sequence has no gap), and its RAW_IMU runs at 2 Hz."""

import re
import struct
import sys
from pathlib import Path

import numpy as np
import pytest
from openpyxl import load_workbook
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation.cli import main
from groundstation.session_makers.load import load_session

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "autopilot"))
from mavlink_helpers import flightlog  # noqa: E402

KEEP_BYTES = 200_000
INJECTED_AT = (500, 1500, 2500)  # after these records
INJECTED_SEQ = (100, 7, 200)


@pytest.fixture(scope="module")
def injected(tmp_path_factory):
    """The log's records as pymavlink reads them, rewritten with three strangers' frames under system 1,
    component 1 (the vehicle's ids) at sequence numbers of their own."""
    source = tmp_path_factory.mktemp("fig") / "cut.tlog"
    source.write_bytes(flightlog("ardusub_rov_surface.tlog").read_bytes()[:KEEP_BYTES])
    log = mavutil.mavlink_connection(str(source))
    records = []
    while (msg := log.recv_match()) is not None:
        if msg.get_type() != "BAD_DATA":
            records.append((int(msg._timestamp * 1e6), bytes(msg.get_msgbuf())))
    stranger = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    out = bytearray()
    for i, (stamp_us, packet) in enumerate(records):
        out += struct.pack(">Q", stamp_us) + packet
        if i in INJECTED_AT:
            stranger.seq = INJECTED_SEQ[INJECTED_AT.index(i)]
            out += struct.pack(">Q", stamp_us) + stranger.named_value_float_encode(0, b"x", 1.0).pack(stranger)
    path = source.parent / "injected.tlog"
    path.write_bytes(bytes(out))
    return path, source


def pymavlink_truth(path) -> dict:
    """The vehicle's (1/1) sequence gaps, RAW_IMU rate and span (of those after its first HEARTBEAT: before
    it, a RAW_IMU's units are not known), by pymavlink alone."""
    log = mavutil.mavlink_connection(str(path))
    last, lost, imu_us, heard = None, 0, [], False
    while (msg := log.recv_match()) is not None:
        if msg.get_type() == "BAD_DATA" or (msg.get_srcSystem(), msg.get_srcComponent()) != (1, 1):
            continue
        if last is not None:
            lost += (msg.get_seq() - last - 1) % 256
        last = msg.get_seq()
        heard = heard or msg.get_type() == "HEARTBEAT"
        if msg.get_type() == "RAW_IMU" and heard:
            imu_us.append(msg.time_usec)
    return {"lost": lost, "imu_rate_hz": 1e6 / float(np.median(np.diff(imu_us))), "imu_span_s": (imu_us[-1] - imu_us[0]) / 1e6}


def number(pattern: str, text: str) -> float:
    match = re.search(pattern, text)
    assert match, (pattern, text)
    return float(match.group(1))


def test_rate_loss_and_duration_are_one_number_in_all_five_places(injected, tmp_path, capsys):
    path, clean = injected
    data = load_session(path, ["ahf"])
    truth = pymavlink_truth(clean)
    assert truth["lost"] == 0  # the log itself has no gap: a stranger's three frames must not make one
    rate, loss, duration = data.imu_rate_hz(), data.link_loss_pct(), data.duration_s()
    assert rate == pytest.approx(truth["imu_rate_hz"], rel=1e-4) and rate == pytest.approx(2.0, abs=0.01)
    assert loss == 0.0 and data.link.counters["frames_lost"] == 0
    assert duration == pytest.approx(truth["imu_span_s"], abs=1e-3)
    places = {}

    # the window: the functions its attitude title and its link panel call, on the file played back to its end
    from groundstation.session.playback import RevealSession
    from groundstation.ui.link_panel import link_figures
    from groundstation.ui.sample_streams import headline

    played = RevealSession(data, path, position_s=float("inf"))
    places["app"] = {"rate": number(r"IMU at ([\d.]+) Hz", headline(played.view)[1]),
                     "loss": link_figures(played, 0)["loss_pct"]}
    # the report
    assert main(["report", str(path), "--filters", "ahf", "--out", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    places["report"] = {"rate": number(r"IMU samples</td><td[^>]*>\d+ at ([\d.]+) Hz", page),
                        "loss": number(r"link loss</td><td[^>]*>([\d.]+) %", page),
                        "duration": number(r"duration</td><td[^>]*>([\d.]+) s", page)}
    # the logbook's dataset
    from groundstation.logbook.summary import summarise

    (tmp_path / "book").mkdir()
    row = summarise(path, path.parent, tmp_path / "book", ["ahf"])[0]
    places["dataset"] = {"rate": row["imu_rate_hz"], "loss": row["link_loss_pct"], "duration": row["duration_s"]}
    # the CLI's totals
    capsys.readouterr()
    assert main(["replay", str(path), "--filters", "ahf"]) == 0
    totals = capsys.readouterr().out.splitlines()[-1]
    places["cli"] = {"rate": number(r"IMU samples at ([\d.]+) Hz", totals), "loss": number(r"lost \(([\d.]+) %\)", totals),
                     "duration": number(r"over ([\d.]+) s", totals)}
    # the workbook's Session sheet
    assert main(["export", str(path), "--filters", "ahf", "--out", str(tmp_path / "w.xlsx")]) == 0
    sheet = {row[0]: row[1] for row in load_workbook(tmp_path / "w.xlsx", read_only=True)["Session"].iter_rows(values_only=True)
             if len(row) > 1 and row[0]}
    places["workbook"] = {"rate": sheet["IMU rate (Hz)"], "loss": sheet["frames lost (%)"], "duration": sheet["duration (s)"]}
    assert sheet["IMU for the estimators"].startswith("RAW_IMU") and "not SCALED_IMU2" in sheet["IMU for the estimators"]

    for place, figures in places.items():
        assert figures["rate"] == pytest.approx(rate, abs=0.05), place  # the texts show one decimal
        assert figures["loss"] == pytest.approx(loss, abs=0.05), place
        if "duration" in figures:
            assert figures["duration"] == pytest.approx(duration, abs=0.05), place

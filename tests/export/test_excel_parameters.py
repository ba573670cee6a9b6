"""The workbook's Parameters sheet (issue 23): an autopilot's parameters by name with their values, and
their changes with times; written by ``groundstation export``, read back with openpyxl, checked against
pyulog and against the values a DataFlash log built here holds."""

import sys
from pathlib import Path

import pytest
from openpyxl import load_workbook
from pyulog import ULog

from groundstation.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "autopilot"))
from mavlink_helpers import flightlog, write_dataflash  # noqa: E402


def parameters_sheet(path):
    rows = list(load_workbook(path, read_only=True)["Parameters"].iter_rows(values_only=True))
    assert rows[0][:2] == ("parameter", "value") and rows[0][3:7] == ("changed at (s)", "parameter", "from", "to")
    values = {r[0]: r[1] for r in rows[1:] if r[0] is not None}
    changes = [tuple(r[3:7]) for r in rows[1:] if len(r) > 3 and r[3] is not None]
    return values, changes


def test_a_ulogs_parameters_are_a_sheet(tmp_path):
    path = flightlog("px4_fmuv5_quad_hop.ulg")
    out = tmp_path / "hop.xlsx"
    assert main(["export", str(path), "--out", str(out), "--filters", "ahf2"]) == 0
    values, changes = parameters_sheet(out)
    expected = {k: float(v) for k, v in ULog(str(path), []).initial_parameters.items()}
    assert values == pytest.approx(expected) and list(values) == sorted(expected)
    assert changes == []


def test_a_change_is_listed_with_its_time(tmp_path):
    log = tmp_path / "plane.bin"
    write_dataflash(log, {
        "MSG": ("QZ", "TimeUS,Message", [(1_000_000, b"ArduPlane V4.5.0 (abcdef12)")]),
        "PARM": ("QNf", "TimeUS,Name,Value", [(1_000_000, b"THR_MAX", 100.0), (1_000_000, b"ARSPD_FBW_MIN", 9.5),
                                             (3_500_000, b"THR_MAX", 80.0)]),
        "ATT": ("Qfff", "TimeUS,Roll,Pitch,Yaw", [(1_000_000 + 40_000 * i, 0.0, 0.0, 90.0) for i in range(100)]),
    })  # fmt: skip
    out = tmp_path / "plane.xlsx"
    assert main(["export", str(log), "--out", str(out)]) == 0
    values, changes = parameters_sheet(out)
    assert values == {"ARSPD_FBW_MIN": 9.5, "THR_MAX": 80.0}
    assert changes == [(2.5, "THR_MAX", 100.0, 80.0)]


def test_a_session_without_parameters_has_no_sheet(sim_recording, tmp_path):
    out = tmp_path / "sim.xlsx"
    assert main(["export", str(sim_recording), "--out", str(out)]) == 0
    assert "Parameters" not in load_workbook(out, read_only=True).sheetnames

"""``groundstation vibration``: text and JSON of a simulated vibrating flight and a real log; wrong input
in one line with exit status 2 (the other refusals: tests/test_cli_refusals.py)."""

import json
from pathlib import Path

import pytest

from groundstation.cli import main

LOG = Path("/work/shared/datasets/flightlogs/arducopter_cubeorange_2023-07-06_10-12-18.bin")


@pytest.fixture(scope="module")
def shaken(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli_vib") / "shake.gsrec"
    assert main(["simulate", "--scenario", "static", "--duration", "20", "--vibration", "22", "--out", str(out)]) == 0
    return out


def test_text_names_the_peak_the_levels_and_the_notch(shaken, capsys):
    assert main(["vibration", str(shaken), "--from", "5", "--what-if", "notch"]) == 0
    out = capsys.readouterr().out
    peaks = [line.split() for line in out.splitlines() if line.strip().startswith("accel") and "motor 1×" in line]
    assert peaks and abs(float(peaks[0][2]) - 22.0) < 2.0
    assert "level accel (RMS above 5 Hz)" in out
    assert "INS_HNTCH_FREQ=22" in out and "IMU_GYRO_NF0_FRQ=22" in out
    assert "what-if: a notch at 22 Hz" in out


def test_json_is_the_summary(shaken, capsys):
    assert main(["vibration", str(shaken), "--from", "5", "--to", "15", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["start_s"] == 5.0 and result["end_s"] == 15.0
    assert result["notch"]["ardupilot"]["INS_HNTCH_ENABLE"] == 1
    assert {p["sensor"] for p in result["peaks"]} == {"gyro", "accel"}


@pytest.mark.skipif(not LOG.exists(), reason="the shared flight logs are not here")
def test_a_real_log_shows_its_clipping(capsys):
    assert main(["vibration", str(LOG)]) == 0
    out = capsys.readouterr().out
    assert "VIBE IMU 0: max" in out and "clips" in out
    assert "throttle" in out


@pytest.mark.parametrize("argv", [["{missing}"], ["{shaken}", "--from", "9", "--to", "3"], ["{shaken}", "--from", "3", "--to", "3.2"]])
def test_wrong_input_is_one_line_and_status_2(shaken, capsys, argv):
    argv = [a.format(missing=shaken.parent / "nothing.gsrec", shaken=shaken) for a in argv]
    assert main(["vibration", *argv]) == 2
    captured = capsys.readouterr()
    said = [line for line in captured.err.splitlines() if line.strip() and "ETA" not in line]  # a progress bar aside
    assert len(said) == 1 and said[0].startswith("groundstation vibration: "), captured.err
    assert captured.out == ""

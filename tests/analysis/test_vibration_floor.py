"""Vibration with a floor: a peak stands above the spectrum's own noise and above a physical minimum
(``vibration.MIN_PEAK``); still data has no peak and no notch, in the CLI and in the report's findings,
while a small real tone above the floor is still found at its amplitude (a sine's, known here)."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from groundstation.analysis import vibration as vib
from groundstation.cli import main
from groundstation.export.report_findings import vibration_findings
from groundstation.session_makers.load import load_session

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from crafted_files import dataset_csv  # noqa: E402

RATE_HZ = 400.0


def test_a_still_file_has_no_peak_and_no_notch(tmp_path, capsys):
    still = dataset_csv(tmp_path, "still", rows=1000)  # gyro 0, acc (0, 0, 9.81): nothing but round-off
    assert main(["vibration", str(still), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["peaks"] == [] and not result["notch"], result
    assert main(["vibration", str(still)]) == 0
    out = capsys.readouterr().out
    assert "motor 1×" not in out and "INS_HNTCH" not in out, out
    summary = vib.vibration_summary(load_session(still, ["ahf"]))
    assert not [f for f in vibration_findings(summary) if f.kind == "vibration_peak"]


@pytest.mark.parametrize("sensor, amplitude, found", [
    ("accel", 0.2, True), ("accel", 0.02, False), ("gyro", 0.2, True), ("gyro", 0.02, False),
])  # fmt: skip
def test_a_tone_counts_only_above_the_physical_floor(sensor, amplitude, found):
    """A 60 Hz sine of ``amplitude`` (m/s² or °/s) over a hundredfold weaker noise: it stands far above the
    spectrum's noise either way; only the floor tells the two apart."""
    t = np.arange(8000) / RATE_HZ
    rng = np.random.default_rng(11)
    x = amplitude * np.sin(2 * np.pi * 60.0 * t)[:, None] + rng.normal(0.0, amplitude / 100, (len(t), 3))
    peaks = vib.find_peaks(vib.spectrum(vib.ImuTable("t", sensor, t, x)))
    assert bool(peaks) == found, peaks
    if found:
        assert peaks[0].frequency_hz == pytest.approx(60.0, abs=0.5) and peaks[0].amplitude == pytest.approx(amplitude, rel=0.05)

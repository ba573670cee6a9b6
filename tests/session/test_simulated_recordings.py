"""Simulated recordings: the truth travels with them, and the samples in recordings/ stay usable."""

from pathlib import Path

import numpy as np
import pytest

from groundstation.recording import open_recording
from groundstation.session_makers.load import load_session
from tests.cli_in_process import run_in_process

SAMPLES = Path(__file__).resolve().parents[2] / "recordings" / "samples"


@pytest.fixture
def gs(capsys):
    return lambda *args: run_in_process(capsys, *args)


def test_a_simulated_recording_scores_like_its_truth_csv(tmp_path, gs):
    """Two roads to the same figures: the recording decoded through the pipeline (body axes, the
    mounting applied) and the truth CSV through the dataset path (sensor axes). They differ only
    by the CSV's 10-digit rounding and the first sample's dt."""
    assert gs("simulate", "--scenario", "slide", "--duration", "40", "--seed", "5", "--out", tmp_path / "s.gsrec").returncode == 0
    assert gs("simulate", "--scenario", "slide", "--duration", "40", "--seed", "5", "--out", tmp_path / "s.bin").returncode == 0
    from_recording = load_session(tmp_path / "s.gsrec", ["hf", "ecf"]).evaluate()
    from_csv = load_session(tmp_path / "s.truth.csv.gz", ["hf", "ecf"]).evaluate()
    for name in ("hf", "ecf"):
        assert from_recording[name]["incl_rmse_deg"] == pytest.approx(from_csv[name]["incl_rmse_deg"], abs=0.1)
        assert from_recording[name]["incl_rmse_deg"] > 0.5  # the slide fools them: the comparison is not trivial


@pytest.mark.parametrize("name", ["hover-raw", "flight-estimated", "flight-both-lossy"])
def test_sample_recordings_are_small_intact_and_scored(name):
    path = SAMPLES / f"{name}.gsrec"
    assert path.stat().st_size < 1_000_000
    recording = open_recording(path)
    assert recording.damage == [] and recording.closed_cleanly
    data = load_session(path)
    assert len(data) > 2500  # 30 s at 100 Hz, after the boot second
    figures = data.evaluate()
    if name == "flight-estimated":
        assert list(figures) == ["onboard"]
    else:
        assert "ahf" in figures
    for values in figures.values():
        assert np.isfinite(values["incl_rmse_deg"]) and values["incl_rmse_deg"] < 20


def test_lossy_sample_counts_its_losses():
    data = load_session(SAMPLES / "flight-both-lossy.gsrec")
    counters = data.link.counters
    assert counters["frames_lost"] > 0 and counters["crc_errors"] > 0

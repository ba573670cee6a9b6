"""A new estimator and a new file format are one registry line each: registered here (and removed
again after the test), they appear in the app (the Open dialog's filter, the estimator panel, the
plots), in ``evaluate`` and in an export, with no other edit."""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groundstation import estimation, formats
from groundstation.cli import main
from groundstation.datasets import trial_from_columns
from groundstation.estimation.ahf import Hf
from groundstation.session_makers.loaders import dataset_csv

from tests.ui.helpers import open_file
from tests.waiting import LIMIT_MS

TRIAL = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "broad" / "02_undisturbed_slow_rotation_B.csv.gz"
needs_dataset = pytest.mark.skipif(not TRIAL.exists(), reason=f"dataset not found at {TRIAL}")


class Twin(Hf):
    """HF's arithmetic under another name: a new estimator whose numbers are known (HF's)."""

    name = "twin"
    label = "Twin"
    colour = "rose"


def load_npz(path, filters=None, forced=None, progress=None):
    """A dataset trial's columns saved by ``numpy.savez``: a format of one function."""
    with np.load(path) as arrays:
        trial = trial_from_columns({name: arrays[name] for name in arrays.files}, path)
    return dataset_csv.session_of_trial(trial, filters, forced, {"source": f"IMU arrays {Path(path).name}"})


NPZ = formats.FileFormat("npz", (".imu.npz",), "IMU arrays", load_npz)


@pytest.fixture
def registered():
    estimation.register(Twin)
    formats.register(NPZ)
    yield
    del estimation.ESTIMATORS[Twin.name]
    del formats.FORMATS[NPZ.name]


@pytest.fixture(scope="module")
def npz_trial(tmp_path_factory) -> Path:
    """20 s of a real BROAD trial around the start of its motion, as arrays."""
    frame = pd.read_csv(TRIAL)
    start = frame.time_s[frame.moving == 1].min() - 5
    frame = frame[(frame.time_s >= start) & (frame.time_s < start + 20)]
    path = tmp_path_factory.mktemp("npz") / "trial.imu.npz"
    np.savez(path, **{name: frame[name].to_numpy(dtype=float) for name in frame.columns})
    return path


@needs_dataset
def test_a_registered_estimator_and_file_format_reach_the_app_the_cli_and_an_export(registered, npz_trial, window,
                                                                                     qtbot, capsys, tmp_path):
    # The app: the Open dialog offers the format; the file opens with the new estimator, which gets its
    # "show" box and its curve, in its colour, under its label.
    assert any("*.imu.npz" in f for f in window.recording_dialog().nameFilters())
    open_file(window, qtbot, npz_trial)
    assert window.banner.isHidden(), window.banner.text()
    assert "twin" in window.session.view.filters
    box = window.estimator_panel.shown["twin"]
    assert box.text() == "Twin"
    box.setChecked(True)
    twin = [c for s, c in window.live_view.attitude.curves if s.label == "Twin"]  # pitch and roll
    assert len(twin) == 2 and {c.opts["pen"].color().name() for c in twin} == {"#cc6677"}  # Tol's muted rose
    qtbot.waitUntil(lambda: all(c.xData is not None and len(c.xData) > 10 for c in twin), timeout=LIMIT_MS)

    # evaluate: the new estimator is among the default ones, and scores as HF (the same arithmetic).
    assert main(["evaluate", str(npz_trial), "--json"]) == 0
    scores = json.loads(capsys.readouterr().out)
    assert "twin" in scores and scores["twin"] == scores["hf"]

    # export: its columns in the CSV, equal to HF's.
    out = tmp_path / "trial.csv"
    assert main(["export", str(npz_trial), "--out", str(out), "--filters", "hf,twin"]) == 0
    table = pd.read_csv(out)
    twin_columns = [c for c in table.columns if c.startswith("twin_")]
    assert twin_columns, list(table.columns)
    for column in twin_columns:
        np.testing.assert_array_equal(table[column], table["hf_" + column.removeprefix("twin_")])

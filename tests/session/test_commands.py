"""The session commands as a user runs them: real files; each command in the test's process (``gs``), and
where a result must not depend on the process (exact figures, byte-identical files) once in a process of its
own (``gs_process``: another interpreter, another hash seed)."""

import filecmp
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from groundstation.datasets import read_csv
from groundstation.estimation.evaluation import evaluate_trial
from tests.cli_in_process import run_in_process

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "datasets" / "broad"
TRIAL = SHARED / "02_undisturbed_slow_rotation_B.csv.gz"
needs_dataset = pytest.mark.skipif(not TRIAL.exists(), reason=f"dataset not found at {TRIAL}")


def gs_process(*args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "groundstation", *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture
def gs(capsys):
    return lambda *args: run_in_process(capsys, *args)


@pytest.fixture(scope="module")
def short_trial(tmp_path_factory) -> Path:
    """20 s of a real trial around the start of its motion, as a plain CSV (keeps the test fast)."""
    path = tmp_path_factory.mktemp("trial") / "trial.csv"
    frame = pd.read_csv(TRIAL)
    start = frame.time_s[frame.moving == 1].min() - 5
    frame[(frame.time_s >= start) & (frame.time_s < start + 20)].to_csv(path, index=False)
    return path


@needs_dataset
def test_imported_trial_evaluates_exactly_as_its_csv(short_trial, tmp_path, gs):
    recording = tmp_path / "trial.gsrec"
    assert gs("import", short_trial, "--out", recording).returncode == 0
    from_recording = json.loads(gs("evaluate", recording, "--filters", "ahf,hf,ecf", "--json").stdout)
    from_csv = json.loads(gs_process("evaluate", short_trial, "--filters", "ahf,hf,ecf", "--json").stdout)
    assert from_recording == from_csv  # exactly, not approximately
    # and both are what the estimators' own evaluation gives on the CSV
    assert from_csv == evaluate_trial(read_csv(short_trial), ["ahf", "hf", "ecf"])


@needs_dataset
def test_export_csv_columns_values_and_byte_identical_reruns(short_trial, tmp_path, gs):
    recording = tmp_path / "trial.gsrec"
    gs("import", short_trial, "--out", recording)
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    assert gs("export", recording, "--out", first, "--filters", "ahf,hf").returncode == 0
    assert gs_process("export", recording, "--out", second, "--filters", "ahf,hf").returncode == 0
    assert filecmp.cmp(first, second, shallow=False)
    table = pd.read_csv(first)
    for name in ("ahf", "hf"):
        for column in ("qw", "qx", "qy", "qz", "pitch_deg", "roll_deg", "yaw_deg"):
            assert f"{name}_{column}" in table.columns
    assert {"time_s", "true_qw", "acc_x_g", "gyr_x_dps"} <= set(table.columns)
    trial = read_csv(short_trial)
    np.testing.assert_allclose(table.time_s, trial.time_s - trial.time_s[0], atol=1e-9)
    # Euler columns agree with the quaternion columns (ZYX, pitch = asin(2(wy - xz)))
    q = table[["ahf_qw", "ahf_qx", "ahf_qy", "ahf_qz"]].to_numpy()
    pitch = np.degrees(np.arcsin(np.clip(2 * (q[:, 0] * q[:, 2] - q[:, 1] * q[:, 3]), -1, 1)))
    np.testing.assert_allclose(table.ahf_pitch_deg, pitch, atol=1e-6)


@needs_dataset
def test_export_time_range_and_rate(short_trial, tmp_path, gs):
    out = tmp_path / "part.csv"
    assert gs("export", short_trial, "--out", out, "--filters", "ahf", "--from", "5", "--to", "10", "--rate", "50").returncode == 0
    table = pd.read_csv(out)
    assert table.time_s.min() >= 5 and table.time_s.max() <= 10
    # 285.7 Hz decimated by 6 -> ~47.6 Hz: about 50 rows a second over 5 s
    assert 200 <= len(table) <= 260


def test_bad_inputs_get_a_message_and_exit_2(tmp_path, gs):
    garbage = tmp_path / "garbage.gsrec"
    garbage.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    cases = [
        ("export", tmp_path / "missing.gsrec", "--out", tmp_path / "x.csv"),
        ("export", garbage, "--out", tmp_path / "x.csv"),
        ("evaluate", garbage),
        ("replay", garbage),
        ("import", tmp_path / "missing.csv", "--out", tmp_path / "x.gsrec"),
        ("export", garbage, "--out", tmp_path / "x.xyz"),
        ("evaluate", garbage, "--set", "hf.nonsense=1"),
    ]
    for case in cases:
        result = gs(*case)
        assert result.returncode == 2, (case, result.stderr)
        assert "Traceback" not in result.stderr and result.stderr.strip(), case
    assert not (tmp_path / "x.csv").exists()


@needs_dataset
def test_export_to_an_unwritable_place_leaves_nothing(short_trial, tmp_path, gs):
    result = gs("export", short_trial, "--out", tmp_path / "no" / "such" / "dir" / "x.csv", "--filters", "ahf")
    assert result.returncode == 2 and "does not exist" in result.stderr
    existing = tmp_path / "exists.csv"
    existing.write_text("keep me")
    result = gs("export", short_trial, "--out", existing, "--filters", "ahf")
    assert result.returncode == 2 and existing.read_text() == "keep me"
    assert gs("export", short_trial, "--out", existing, "--filters", "ahf", "--overwrite").returncode == 0
    assert existing.read_text().startswith("time_s,")
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")] == []

"""Damage to an imported recording costs the rows it hit and nothing else: the intact rows keep their
own times, and records repeated by a duplicated byte range are said once, never replayed twice."""

import numpy as np

from groundstation.cli import main
from groundstation.session_makers.load import load_session
from tests.crafted_files import byte_range_duplicated, dataset_csv, first_samples_block_damaged


def imported(tmp_path, **kwargs):
    csv = dataset_csv(tmp_path, **kwargs)
    out = tmp_path / "trial.gsrec"
    assert main(["import", str(csv), "--out", str(out)]) == 0
    return csv, out


def test_losing_the_first_block_keeps_every_intact_rows_time(tmp_path):
    csv, path = imported(tmp_path)
    intact = load_session(path)
    first_samples_block_damaged(path)
    damaged = load_session(path)
    assert damaged.damage and "failed its CRC" in damaged.damage[0]
    lost = len(intact.time_s) - len(damaged.time_s)
    assert 0 < lost < len(intact.time_s)
    # the rows that survive are the CSV's last rows, at the CSV's own times (row k at k / 100 s)
    np.testing.assert_array_equal(damaged.time_s, intact.time_s[lost:])
    assert damaged.time_s[0] == lost / 100.0


def test_the_export_keeps_the_rows_times(tmp_path):
    _, path = imported(tmp_path)
    first_samples_block_damaged(path)
    out = tmp_path / "out.csv"
    assert main(["export", str(path), "--out", str(out)]) == 0
    import pandas as pd

    exported = pd.read_csv(out, comment="#")
    assert exported["time_s"].iloc[0] == 11.7  # the first intact row: row 1170 of the CSV, at 1170 / 100 s


def test_a_duplicated_byte_range_gives_no_extra_rows(tmp_path):
    from tests.crafted_files import _recording

    path = _recording(tmp_path, "link", {"source": "crafted"})
    intact = load_session(path)
    byte_range_duplicated(path)
    damaged = load_session(path)
    repeats = [d for d in damaged.damage if "repeat" in d]
    assert len(repeats) == 1, (damaged.damage, len(damaged.time_s), len(intact.time_s))  # said once, however many records repeat
    # Only the records cut at the two ends of the repeated range are lost; the repeated ones count once.
    assert len(damaged.time_s) <= len(intact.time_s)
    assert np.all(np.diff(damaged.time_s) > 0)
    assert np.isin(damaged.time_s, intact.time_s).all()


def test_an_imported_recording_with_a_duplicated_range_has_each_row_once(tmp_path):
    _, path = imported(tmp_path, rows=20_000)
    byte_range_duplicated(path, length_fraction=0.3)  # several whole blocks of samples repeated
    damaged = load_session(path)
    assert any("repeat" in d for d in damaged.damage), damaged.damage
    assert np.all(np.diff(damaged.time_s) > 0) and len(damaged.time_s) <= 20_000

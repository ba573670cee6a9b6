"""CSV and Parquet written a stretch of rows at a time: the same bytes as the whole table written at once."""

import subprocess
import sys

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

from groundstation.export.columns import export_columns, export_stretches, select_rows
from groundstation.export.tabular import arrow_array, write_csv, write_parquet

STRETCH = 400  # rows: the 20 s session (~900 rows at 50 Hz) in a few stretches, the last one short


@pytest.fixture(scope="module")
def rows(sim_session):
    rows = select_rows(sim_session.time_s, t_from=1.0, rate_hz=50.0)  # a range and a decimation: rows not 0..n
    assert len(rows) > 2 * STRETCH and len(rows) % STRETCH
    return rows


def test_the_stretches_are_the_whole_columns_cut(sim_session, rows):
    whole = export_columns(sim_session, rows)
    stretches = list(export_stretches(sim_session, rows, STRETCH))
    assert len(stretches) == -(-len(rows) // STRETCH)
    for name, values in whole.items():
        joined = np.concatenate([stretch[name] for stretch in stretches])
        assert joined.tobytes() == np.asarray(values).tobytes(), name  # NaN, -0.0 and all, bit for bit
    assert np.count_nonzero(~np.isnan(whole["gps_lat_deg"])) > 0  # the readings' columns are among them


def test_parquet_by_stretches_is_the_whole_table_written_at_once(sim_session, rows, tmp_path):
    write_parquet(export_stretches(sim_session, rows, STRETCH), tmp_path / "stretches.parquet")
    whole = export_columns(sim_session, rows)
    # pyarrow's own whole-table write, NaN as null (as pandas' writer stored it), row groups of the stretch's
    # size, no dictionary encoding (``write_parquet``'s choice)
    table = pa.table({name: pa.array(v, from_pandas=v.dtype.kind == "f") for name, v in whole.items()})
    pq.write_table(table, tmp_path / "whole.parquet", row_group_size=STRETCH, use_dictionary=False)
    assert (tmp_path / "stretches.parquet").read_bytes() == (tmp_path / "whole.parquet").read_bytes()
    assert pq.ParquetFile(tmp_path / "stretches.parquet").metadata.num_row_groups == len(list(range(0, len(rows), STRETCH)))


def test_csv_by_stretches_is_the_whole_table_written_at_once(sim_session, rows, tmp_path):
    write_csv(export_stretches(sim_session, rows, STRETCH), tmp_path / "stretches.csv")
    write_csv(export_columns(sim_session, rows), tmp_path / "whole.csv")
    assert (tmp_path / "stretches.csv").read_bytes() == (tmp_path / "whole.csv").read_bytes()
    back = pacsv.read_csv(tmp_path / "stretches.csv")
    assert back.num_rows == len(rows) and back.column_names == list(export_columns(sim_session, rows))


@pytest.mark.parametrize("suffix", ["parquet", "csv"])
def test_an_export_loads_no_library_it_does_not_use(sim_recording, tmp_path, suffix):
    """``groundstation export X.parquet`` / ``X.csv`` in a fresh process: pandas (pyarrow's ``pa.array`` imports it
    to look for pandas objects, ~40 MB) and openpyxl (the workbook's, ~27 MB) are never loaded."""
    script = (
        "import sys\n"
        "from groundstation.export.request import export_request, run_export\n"
        "from groundstation.session_makers.load import load_session\n"
        f"run_export(export_request({str(sim_recording)!r}, {str(tmp_path / ('x.' + suffix))!r}, filters=['ahf']), load_session)\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'pandas', 'openpyxl'}))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "[]"


def test_arrow_arrays_are_pyarrows_own():
    rng = np.random.default_rng(7)
    floats = rng.normal(size=(1000, 4))
    floats[rng.random(floats.shape) < 0.3] = np.nan
    columns = [floats[:, 1], floats[:, 2].copy(), np.full(9, np.nan), np.array([]), np.array([-0.0, 1.5]),
               rng.integers(-5, 5, 100), rng.integers(0, 9, 100).astype(np.uint16), rng.random(77) < 0.5]
    for values in columns:  # a strided column, whole, every value NaN, none, -0.0, ints, unsigned, booleans
        for as_null in (True, False):
            mine, theirs = arrow_array(values, as_null), pa.array(values, from_pandas=as_null and values.dtype.kind == "f")
            assert mine.type == theirs.type and mine.is_null().equals(theirs.is_null()), (values.dtype, as_null)  # NaN != NaN: no equals
            assert np.asarray(mine.to_numpy(zero_copy_only=False)).tobytes() == np.asarray(theirs.to_numpy(zero_copy_only=False)).tobytes()

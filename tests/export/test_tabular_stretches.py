"""CSV and Parquet written a stretch of rows at a time: the same bytes as the whole table written at once."""

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest

from groundstation.export.columns import export_columns, export_stretches, select_rows
from groundstation.export.tabular import write_csv, write_parquet

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

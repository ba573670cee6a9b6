"""The tables of a folder run (``evaluate DIR --out OUT``: ``OUT/tables/<table>/log_id=<id>/``) as one
dataset per table, read whole by others' readers: DuckDB's ``read_parquet`` (without ``union_by_name``),
polars' ``scan_parquet`` and ``pyarrow.dataset`` find every column any log has, a value a log lacks is
null (never NaN), and ``avg()`` of a column with gaps is a number, on a folder of a .tlog, a .bin, a .ulg
and a simulated recording. The truth: each log opened alone (``load_session``)."""

import math
import shutil
from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.dataset as ds
import pytest

from groundstation.logbook.folder import evaluate_folder
from groundstation.logbook.summary import log_id
from groundstation.session_makers.load import load_session
from tests.simulated import simulated_chunks, write_recording

LOGS = Path(__file__).resolve().parents[1].parent / "shared" / "datasets" / "flightlogs"
CHOSEN = ("arduplane_quadplane_sitl.tlog", "arduplane_omnibusf4_ground_pilot_0004.bin", "px4_fmuv5_quad_hop.ulg")
FILTERS = ["ahf", "hf"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    if not LOGS.exists():
        pytest.skip(f"flight logs not found at {LOGS}")
    root = tmp_path_factory.mktemp("mixed")
    for name in CHOSEN:
        shutil.copy(LOGS / name, root / name)
    write_recording(root / "sim.gsrec", simulated_chunks(5.0, seed=11, loss=0.02, mag_rate_hz=50),
                    {"start_utc": "2024-05-01T12:00:00Z"})
    out = tmp_path_factory.mktemp("out") / "dataset"
    evaluate_folder(root, out, FILTERS, workers=2)
    alone = {log_id(path, root): load_session(path, FILTERS, exact=True) for path in sorted(root.iterdir())}
    return out / "tables", alone


def shared_tables(alone) -> dict[str, dict[str, list[str]]]:
    """table -> log id -> its columns, for the tables more than one log has."""
    found: dict[str, dict[str, list[str]]] = {}
    for identifier, data in alone.items():
        for name, columns in data.tables.items():
            if len(columns["time_s"]):
                found.setdefault(name, {})[identifier] = list(columns)
    return {name: logs for name, logs in found.items() if len(logs) > 1}


def test_every_reader_reads_every_column_of_every_table(run):
    import duckdb
    import polars as pl

    tables, alone = run
    shared = shared_tables(alone)
    assert any(len({tuple(c) for c in logs.values()}) > 1 for logs in shared.values())  # the logs' columns differ
    for name, logs in shared.items():
        every = {c for columns in logs.values() for c in columns}
        rows = sum(len(alone[i].tables[name]["time_s"]) for i in logs)
        files = f"{tables / name}/*/*.parquet"
        duck = duckdb.sql(f"SELECT * FROM read_parquet('{files}', hive_partitioning=true)")
        assert every | {"log_id"} == set(duck.columns), name
        assert duckdb.sql(f"SELECT count(*) FROM read_parquet('{files}')").fetchall()[0][0] == rows
        polars = pl.scan_parquet(tables / name).collect()
        assert every <= set(polars.columns) and polars.height == rows, name
        arrow = ds.dataset(tables / name, partitioning="hive").to_table()
        assert every <= set(arrow.column_names) and arrow.num_rows == rows, name
        for identifier, columns in logs.items():  # each log's values, its missing columns null
            mine = arrow.filter(pc.equal(arrow["log_id"], identifier))
            for column in every:
                values = mine[column]
                assert pc.sum(pc.is_nan(values)).as_py() in (0, None), f"{name}.{column}: NaN written"
                if column in columns:
                    want = np.asarray(alone[identifier].tables[name][column], dtype=float)
                    got = values.to_numpy(zero_copy_only=False)
                    np.testing.assert_array_equal(got, want, err_msg=f"{name}.{column}")
                else:
                    assert values.null_count == len(values), f"{name}.{column} of {identifier}"


def test_the_average_of_a_column_with_gaps_is_a_number(run):
    import duckdb

    tables, alone = run
    shared = shared_tables(alone)
    # A column some logs have and others lack (host_time_s: a .tlog's and a recording's receive times).
    name, column = next((n, c) for n, logs in shared.items() for c in sorted({c for cs in logs.values() for c in cs})
                        if any(c not in cs for cs in logs.values()))
    values = np.concatenate([np.asarray(alone[i].tables[name][column], dtype=float) for i in shared[name]
                             if column in alone[i].tables[name]])
    average = duckdb.sql(f"SELECT avg({column}) FROM read_parquet('{tables / name}/*/*.parquet')").fetchall()[0][0]
    assert average is not None and math.isfinite(average)
    assert average == pytest.approx(np.nanmean(values), rel=1e-12)

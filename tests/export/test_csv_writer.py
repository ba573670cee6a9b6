"""write_csv against the pandas writer it replaces: the same bytes, for any numbers and for a session."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from groundstation.export.columns import export_columns
from groundstation.export.tabular import CSV_FLOAT_FORMAT, write_csv


def pandas_csv(columns: dict, path) -> None:
    """The writer before (groundstation 0.1): the reference layout."""
    pd.DataFrame(columns).to_csv(path, index=False, float_format=CSV_FLOAT_FORMAT, lineterminator="\n")


def assert_same_bytes(columns: dict, tmp_path) -> None:
    write_csv(columns, tmp_path / "ours.csv")
    pandas_csv(columns, tmp_path / "pandas.csv")
    assert (tmp_path / "ours.csv").read_bytes() == (tmp_path / "pandas.csv").read_bytes()


any_float = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
column_kinds = st.sampled_from([(np.float64, any_float), (np.float32, st.floats(width=32)), (np.int64, st.integers(-(2**63), 2**63 - 1)), (np.uint8, st.integers(0, 255)), (np.bool_, st.booleans())])


@settings(max_examples=100, derandomize=True, deadline=None)
@given(st.integers(0, 30).flatmap(lambda n: st.lists(column_kinds.flatmap(lambda k: arrays(k[0], n, elements=k[1])), min_size=1, max_size=6)))
def test_any_numbers_give_the_pandas_bytes(tmp_path_factory, arrays_):
    columns = {f"col_{i}": a for i, a in enumerate(arrays_)}
    assert_same_bytes(columns, tmp_path_factory.mktemp("csv"))


def test_more_rows_than_one_write_and_every_float_class(tmp_path):
    rng = np.random.default_rng(5)
    n = 45_001  # beyond two of the writer's blocks
    columns = {"time_s": np.arange(n) * 0.01}
    for exponent in (-320, -8, -5, -4, 0, 9, 10, 16, 300):
        columns[f"e{exponent}"] = rng.normal(0.0, 1.0, n) * 10.0**exponent
    columns["gaps"] = np.where(rng.random(n) < 0.1, np.nan, rng.normal(size=n))
    columns["specials"] = rng.choice([math.inf, -math.inf, -0.0, 0.0, math.nan, 1e-310], n)
    assert_same_bytes(columns, tmp_path)


def test_simulated_session_export_is_unchanged(sim_session, tmp_path):
    columns = export_columns(sim_session)
    assert any(np.isnan(v).any() for v in columns.values())  # the session has gaps: rows of NaN
    assert_same_bytes(columns, tmp_path)


def test_a_column_that_is_not_a_number_is_refused(tmp_path):
    with pytest.raises(TypeError, match="'name'"):
        write_csv({"time_s": np.zeros(2), "name": np.array(["a", "b"])}, tmp_path / "out.csv")

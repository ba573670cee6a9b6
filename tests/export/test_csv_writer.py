"""write_csv: pyarrow's writer with NaN as an empty field; every number reads back bit for bit."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from groundstation.export.columns import export_columns
from groundstation.export.tabular import write_csv


def read_back(path, columns: dict) -> dict:
    """The file parsed by Python (float() is correctly rounded), each column in its written dtype."""
    lines = path.read_text().splitlines()
    cells = list(zip(*(line.split(",") for line in lines[1:])))
    parse = {"f": lambda c: float(c) if c else math.nan, "b": lambda c: {"true": True, "false": False}[c], "i": int, "u": int}
    return {name: np.array([parse[v.dtype.kind](c) for c in column]).astype(v.dtype)
            for (name, v), column in zip(columns.items(), cells)}


def assert_reads_back(columns: dict, path) -> None:
    write_csv(columns, path)
    assert path.read_text().splitlines()[0] == ",".join(columns)  # the header: the names, unquoted
    back = read_back(path, columns)
    for name, values in columns.items():
        got = back[name]
        assert np.array_equal(got, values, equal_nan=values.dtype.kind == "f"), name
        if values.dtype.kind == "f":
            assert np.array_equal(np.signbit(got[got == 0]), np.signbit(values[values == 0])), name  # -0.0 too


any_float = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
column_kinds = st.sampled_from([(np.float64, any_float), (np.float32, st.floats(width=32)), (np.int64, st.integers(-(2**63), 2**63 - 1)),
                                (np.uint8, st.integers(0, 255)), (np.bool_, st.booleans())])


@settings(max_examples=100, derandomize=True)
@given(st.integers(1, 30).flatmap(lambda n: st.lists(column_kinds.flatmap(lambda k: arrays(k[0], n, elements=k[1])), min_size=2, max_size=6)))
def test_any_numbers_read_back_bit_for_bit(tmp_path_factory, arrays_):
    columns = {f"col_{i}": a for i, a in enumerate(arrays_)}
    assert_reads_back(columns, tmp_path_factory.mktemp("csv") / "out.csv")


def test_nan_is_an_empty_field_and_floats_are_their_shortest_text(tmp_path):
    columns = {"time_s": np.array([0.0, 0.01, 0.02]), "x": np.array([0.1, math.nan, -0.0]), "n": np.array([1, 2, 3])}
    write_csv(columns, tmp_path / "out.csv")
    assert (tmp_path / "out.csv").read_text() == "time_s,x,n\n0,0.1,1\n0.01,,2\n0.02,-0,3\n"


def test_a_lone_column_keeps_nan_as_text_not_a_blank_line(tmp_path):
    write_csv({"x": np.array([1.5, math.nan, 2.0])}, tmp_path / "out.csv")
    assert (tmp_path / "out.csv").read_text() == "x\n1.5\nnan\n2\n"
    assert np.array_equal(pd.read_csv(tmp_path / "out.csv")["x"].to_numpy(), [1.5, math.nan, 2.0], equal_nan=True)


def test_many_rows_and_every_float_class(tmp_path):
    rng = np.random.default_rng(5)
    n = 45_001
    columns = {"time_s": np.arange(n) * 0.01}
    for exponent in (-320, -8, -5, -4, 0, 9, 10, 16, 300):
        columns[f"e{exponent}"] = rng.normal(0.0, 1.0, n) * 10.0**exponent
    columns["gaps"] = np.where(rng.random(n) < 0.1, np.nan, rng.normal(size=n))
    columns["specials"] = rng.choice([math.inf, -math.inf, -0.0, 0.0, math.nan, 1e-310], n)
    assert_reads_back(columns, tmp_path / "out.csv")


def test_simulated_session_export_reads_back(sim_session, tmp_path):
    columns = export_columns(sim_session)
    assert any(np.isnan(v).any() for v in columns.values())  # the session has gaps: rows of NaN
    assert_reads_back(columns, tmp_path / "out.csv")


def test_a_column_that_is_not_a_number_is_refused(tmp_path):
    with pytest.raises(TypeError, match="'name'"):
        write_csv({"time_s": np.zeros(2), "name": np.array(["a", "b"])}, tmp_path / "out.csv")

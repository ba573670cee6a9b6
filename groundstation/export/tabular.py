"""CSV and Parquet from the export columns."""

from __future__ import annotations

import importlib.util

import numpy as np
import pandas as pd

from groundstation.errors import UserError
from groundstation.export.files import atomic_output

CSV_FLOAT_FORMAT = "%.10g"  # fixed, so identical input gives byte-identical files
_CSV_ROWS_PER_WRITE = 20_000  # bounds the text held in memory (a few MB), whatever the session length


def write_csv(columns: dict, path, overwrite: bool = False) -> None:
    """The layout ``DataFrame.to_csv(index=False, float_format=CSV_FLOAT_FORMAT)`` writes, byte for
    byte: floats as ``%.10g``, NaN as an empty field, integers in full, booleans as True/False.

    Each row is formatted by one ``%`` of a row template (the per-value work happens in C), several
    times faster than pandas' formatter; pyarrow's CSV writer is faster still but writes floats as
    their shortest round-trip repr, not ``%.10g`` (bench/bench_csv.py).
    """
    values = [np.asarray(v) for v in columns.values()]
    row_format = ",".join(_csv_format(name, v.dtype) for name, v in zip(columns, values)) + "\n"
    with atomic_output(path, overwrite) as temporary, open(temporary, "w", encoding="utf-8", newline="") as out:
        out.write(",".join(columns) + "\n")
        for start in range(0, len(values[0]) if values else 0, _CSV_ROWS_PER_WRITE):
            rows = zip(*(v[start : start + _CSV_ROWS_PER_WRITE].tolist() for v in values))
            # "%.10g" % nan is "nan", the only token that can contain those letters; pandas writes "".
            text = "".join(map(row_format.__mod__, rows)).replace("nan", "")
            if len(values) == 1:  # a lone empty field would be a blank line, which readers skip: quoted, as pandas does
                text = "".join('""\n' if line == "\n" else line for line in text.splitlines(keepends=True))
            out.write(text)


def _csv_format(name: str, dtype: np.dtype) -> str:
    if dtype.kind == "f":
        return CSV_FLOAT_FORMAT
    if dtype.kind in "iu":
        return "%d"
    if dtype.kind == "b":
        return "%s"
    raise TypeError(f"CSV export: column {name!r} has dtype {dtype}, not a number")


def require_pyarrow() -> None:
    """Parquet needs the optional pyarrow (pandas uses it): a clear message, not pandas' ImportError."""
    if importlib.util.find_spec("pyarrow") is None:
        raise UserError("Parquet export needs pyarrow: pip install 'groundstation[parquet]'")


def write_parquet(columns: dict, path, overwrite: bool = False) -> None:
    require_pyarrow()
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_parquet(temporary, index=False)

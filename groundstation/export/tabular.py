"""CSV and Parquet from the export columns."""

from __future__ import annotations

import numpy as np
import pandas as pd

from groundstation.export.files import atomic_output


def write_csv(columns: dict, path, overwrite: bool = False) -> None:
    """pyarrow's CSV writer (C++, several times faster than formatting in Python): a header of the
    column names, then one line per row; floats as their shortest round-trip text (read back, every
    value is the float64 written, bit for bit), NaN as an empty field, integers in full, booleans as
    ``true``/``false``. A table of one column keeps NaN as ``nan``: an empty field there would be a
    blank line, which readers skip.

    Until this writer, CSV floats were pandas' ``%.10g`` (ten significant digits, formatted in Python
    at 2.75x a bare pyarrow write; bench/bench_csv.out.md): now they are exact, and files of filter
    quaternions are up to 1.5x larger.
    """
    import pyarrow as pa
    import pyarrow.csv as pacsv

    values = [np.asarray(v) for v in columns.values()]
    for name, v in zip(columns, values):
        if v.dtype.kind not in "fiub":
            raise TypeError(f"CSV export: column {name!r} has dtype {v.dtype}, not a number")
    empty_nan = len(values) > 1
    arrays = [pa.array(v, from_pandas=empty_nan and v.dtype.kind == "f") for v in values]
    table = pa.Table.from_arrays(arrays, names=list(columns))
    with atomic_output(path, overwrite) as temporary, open(temporary, "wb") as out:
        out.write((",".join(columns) + "\n").encode())  # pyarrow would quote the names
        pacsv.write_csv(table, out, pacsv.WriteOptions(include_header=False, quoting_style="none"))


def write_parquet(columns: dict, path, overwrite: bool = False) -> None:
    with atomic_output(path, overwrite) as temporary:
        pd.DataFrame(columns).to_parquet(temporary, index=False)

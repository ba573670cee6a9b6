"""CSV and Parquet from the export columns: their writers in ``export.request.FORMATS``."""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np

from groundstation.export.columns import export_stretches, select_rows
from groundstation.export.files import atomic_output


def export_csv(data, request, writing, cancel) -> tuple[str, list[str]]:
    return _export_rows(write_csv, data, request)


def export_parquet(data, request, writing, cancel) -> tuple[str, list[str]]:
    return _export_rows(write_parquet, data, request)


def _export_rows(write: Callable, data, request) -> tuple[str, list[str]]:
    """The session's rows a stretch at a time; the columns kept apart (``columns.aux_columns``) said as warnings."""
    rows = select_rows(data.time_s, request.t_from, request.t_to, request.rate_hz)
    renamed: list[str] = []
    stretches = export_stretches(data, rows, renamed=renamed)
    first = next(stretches)
    columns, chained = len(first), _first_then(first, stretches)
    del first  # each stretch is freed once written
    write(chained, request.out, request.overwrite)
    return f"{len(rows)} rows, {columns} columns", renamed


def _first_then(first, rest):
    """``first``, then the items of ``rest``, holding none once handed on (``itertools.chain([first], rest)``
    would hold ``first`` to the end)."""
    yield first
    del first
    yield from rest


def write_csv(columns: dict | Iterable[dict], path, overwrite: bool = False) -> None:
    """pyarrow's CSV writer (C++, several times faster than formatting in Python): a header of the
    column names, then one line per row; floats as their shortest round-trip text (read back, every
    value is the float64 written, bit for bit), NaN as an empty field, integers in full, booleans as
    ``true``/``false``. A table of one column keeps NaN as ``nan``: an empty field there would be a
    blank line, which readers skip.

    Until this writer, CSV floats were pandas' ``%.10g`` (ten significant digits, formatted in Python
    at 2.75x a bare pyarrow write; bench/bench_csv.out.md): now they are exact, and files of filter
    quaternions are up to 1.5x larger.
    """
    import pyarrow.csv as pacsv

    with atomic_output(path, overwrite) as temporary, open(temporary, "wb") as out:
        writer = None
        for batch in record_batches(columns, empty_nan=None):
            if writer is None:
                out.write((",".join(batch.schema.names) + "\n").encode())  # pyarrow would quote the names
                writer = pacsv.CSVWriter(out, batch.schema, write_options=pacsv.WriteOptions(include_header=False, quoting_style="none"))
            writer.write_batch(batch)
            del batch
        writer.close()


def write_parquet(columns: dict | Iterable[dict], path, overwrite: bool = False) -> None:
    """Parquet straight from the arrays (no DataFrame copy), a row group per stretch of rows
    (``columns.export_stretches``), so the writer holds one stretch at a time; NaN is stored as null, as
    pandas' writer did. The same bytes as ``pyarrow.parquet.write_table`` of the whole table with that
    row-group size (tests/export/test_tabular_stretches.py). No dictionary encoding: a session's columns are
    floats that rarely repeat, and trying a dictionary on each took 4.5x the time of the whole write for a
    larger file (bench/bench_export_memory.out.md)."""
    import pyarrow.parquet as pq

    with atomic_output(path, overwrite) as temporary:
        writer = None
        for batch in record_batches(columns, empty_nan=True):
            if writer is None:
                writer = pq.ParquetWriter(temporary, batch.schema, use_dictionary=False)
            writer.write_batch(batch, row_group_size=max(batch.num_rows, 1))
            del batch  # freed before the next stretch is made: one stretch in memory at a time
        writer.close()


def record_batches(columns: dict | Iterable[dict], empty_nan: bool | None):
    """Each stretch of export columns (one dict: the whole) as a pyarrow record batch, numbers only
    (TypeError names a column that is not). ``empty_nan``: NaN as null in float columns; None: so
    unless the table has a single column (its null would be a blank CSV line, which readers skip)."""
    import pyarrow as pa

    whole = isinstance(columns, dict)
    for stretch in [columns] if whole else columns:
        names = list(stretch)
        for name, v in stretch.items():
            if np.asarray(v).dtype.kind not in "fiub":
                raise TypeError(f"export: column {name!r} has dtype {np.asarray(v).dtype}, not a number")
        as_null = len(names) > 1 if empty_nan is None else empty_nan
        arrays = []
        for name in names:  # a stretch's column leaves it as converted: its arrow array then holds it alone (shared)
            arrays.append(arrow_array(stretch[name] if whole else stretch.pop(name), as_null))
        batch = pa.RecordBatch.from_arrays(arrays, names=names)
        del stretch, arrays  # nothing of this stretch held here while the next one is made
        yield batch
        del batch


def arrow_array(values, nan_as_null: bool = False, missing: np.ndarray | None = None):
    """A column of numbers as a pyarrow array, the one ``pa.array(values, from_pandas=nan_as_null, mask=missing)``
    makes (the data shared, not copied; null where ``missing`` says, or where a float is NaN if ``nan_as_null``),
    built from its buffers: ``pa.array`` imports pandas to look for pandas objects (~40 MB of an export's process,
    never used). The CSV, Parquet and workbook writers' one way to arrow."""
    import pyarrow as pa

    values = np.ascontiguousarray(values)
    kind = values.dtype.kind
    data = np.packbits(values, bitorder="little") if kind == "b" else values  # arrow's booleans are bits
    if nan_as_null and kind == "f":
        missing = np.isnan(values)
    nulls = 0 if missing is None else int(np.count_nonzero(missing))
    validity = pa.py_buffer(np.packbits(~missing, bitorder="little")) if nulls else None
    return pa.Array.from_buffers(pa.from_numpy_dtype(values.dtype), len(values), [validity, pa.py_buffer(data)], nulls)

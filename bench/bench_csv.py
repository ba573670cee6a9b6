"""CSV export writer against a bare pyarrow CSV write of the same table, and pandas' to_csv (the writer before).

    PYTHONPATH=. python bench/bench_csv.py [--rows N] [--repeats R]

The table is shaped like an export with three estimators and the sensors: 40 float64 columns of
values over many magnitudes, 1% of the rows NaN (gaps), ``time_s`` at 100 Hz. The export writes
through pyarrow too (NaN as an empty field, its own header line); the bare write is the same table
with NaN written as ``nan``. Medians of R repeats, to files in a temporary folder.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv

from timing import median_seconds

from groundstation.export.tabular import write_csv

CSV_FLOAT_FORMAT = "%.10g"  # the writer before


def export_like(n: int, width: int = 40) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(2)
    columns = {"time_s": np.arange(n) * 0.01}
    for i in range(width - 1):
        columns[f"c{i}"] = rng.normal(0.0, 10.0 ** (i % 8 - 3), n)
    gaps = rng.random(n) < 0.01
    for values in list(columns.values())[1:]:
        values[gaps] = np.nan
    return columns


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    columns = export_like(args.rows)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        arrow = median_seconds(lambda: pacsv.write_csv(pa.table(columns), out / "arrow.csv"), args.repeats)
        ours = median_seconds(lambda: write_csv(columns, out / "ours.csv", overwrite=True), args.repeats)
        panda = median_seconds(
            lambda: pd.DataFrame(columns).to_csv(out / "pandas.csv", index=False, float_format=CSV_FLOAT_FORMAT, lineterminator="\n"),
            args.repeats,
        )
        back = pd.read_csv(out / "ours.csv")
        assert all(np.array_equal(back[name].to_numpy(), values, equal_nan=True) for name, values in columns.items())
        size = (out / "ours.csv").stat().st_size
        size_pandas = (out / "pandas.csv").stat().st_size
    print(f"{args.rows} rows x {len(columns)} columns ({size / 1e6:.1f} MB of CSV; %.10g: {size_pandas / 1e6:.1f} MB); medians of {args.repeats}")
    print(f"bare pyarrow write_csv (baseline):   {arrow:6.2f} s")
    print(f"write_csv (export, exact floats):    {ours:6.2f} s  ({ours / arrow:.2f} x baseline)")
    print(f"pandas to_csv %.10g:                 {panda:6.2f} s  ({panda / arrow:.2f} x baseline; {panda / ours:.1f} x write_csv)")


if __name__ == "__main__":
    main()

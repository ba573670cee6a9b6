"""Table append cost per row and read cost, against the bare ``array('d').extend`` the old Table was.

    PYTHONPATH=. python bench/bench_table.py [--rows N] [--repeats R]

Rows of 20 floats (the width of the IMU table with three estimators), appended one by one as the live
pipeline does; the baseline is the old Table's whole append (a bound ``array('d').extend``), measured
in the same run. Also: ``extend`` of the same rows as one array (the batch path), ``column`` (one
column) and ``array`` (everything) on the filled table; medians of R repeats.
"""

from __future__ import annotations

import argparse
from array import array

import numpy as np

from timing import median_seconds

from groundstation.session_parts.table import Table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=360_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n, width = args.rows, 20
    columns = [f"c{i}" for i in range(width)]
    rows = [tuple(float(k + i) for i in range(width)) for k in range(n)]
    data = np.array(rows)

    def bare():
        append = array("d").extend
        for row in rows:
            append(row)

    def table():
        append = Table(columns).append
        for row in rows:
            append(row)

    base = median_seconds(bare, args.repeats)
    new = median_seconds(table, args.repeats)
    bulk = median_seconds(lambda: Table(columns).extend(data), args.repeats)
    filled = Table(columns)
    filled.extend(data)
    column = median_seconds(lambda: filled.column("c3"), args.repeats)
    whole = median_seconds(filled.array, args.repeats)
    print(f"{n} rows x {width} columns; medians of {args.repeats}")
    print(f"baseline array('d').extend (old Table.append): {base / n * 1e9:7.1f} ns/row")
    print(f"Table.append:                                  {new / n * 1e9:7.1f} ns/row  ({new / base:.2f} x baseline)")
    print(f"Table.extend of one (N, {width}) array:             {bulk / n * 1e9:7.1f} ns/row  ({bulk / base:.3f} x baseline)")
    print(f"column(): {column * 1e3:.2f} ms   array(): {whole * 1e3:.2f} ms   (one column copied vs all {width})")


if __name__ == "__main__":
    main()

"""``groundstation export``: a session (recording or dataset CSV) to CSV or Parquet."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.commands.options import add_estimator_options, estimator_options
from groundstation.commands.progress import ProgressBar
from groundstation.errors import UserError

FORMATS = (".csv", ".parquet", ".xlsx")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="a recording (.gsrec) or a dataset CSV")
    parser.add_argument("--out", required=True, type=Path, metavar="OUT", help="OUT.csv or OUT.parquet (by extension)")
    add_estimator_options(parser, None)
    parser.add_argument("--from", dest="t_from", type=float, metavar="S", help="first second to export")
    parser.add_argument("--to", dest="t_to", type=float, metavar="S", help="last second to export")
    parser.add_argument("--rate", type=float, metavar="HZ", help="decimate to about HZ samples per second")
    parser.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    from groundstation.export.columns import export_columns, select_rows
    from groundstation.export.tabular import write_csv, write_parquet
    from groundstation.session.data import load_session

    suffix = args.out.suffix.lower()
    if suffix not in FORMATS:
        raise UserError(f"--out must end in {', '.join(FORMATS)}, not {args.out.name}")
    if suffix == ".xlsx":
        raise UserError("Excel export is not built yet; export to .csv or .parquet")
    if args.out.exists() and not args.overwrite:
        raise UserError(f"{args.out} exists; choose another name or pass --overwrite")
    filters, overrides = estimator_options(args)
    bar = ProgressBar("decoding")
    data = load_session(args.file, filters, overrides, bar)
    bar.done()
    columns = export_columns(data, select_rows(data.time_s, args.t_from, args.t_to, args.rate))
    (write_csv if suffix == ".csv" else write_parquet)(columns, args.out, args.overwrite)
    for finding in data.damage:
        print(f"warning: {finding}")
    print(f"wrote {args.out}: {len(columns['time_s'])} rows, {len(columns)} columns")
    return 0

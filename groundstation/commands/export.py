"""``groundstation export``: a session (recording or dataset CSV) to CSV, Parquet or an Excel workbook."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.commands.options import add_estimator_options, estimator_options
from groundstation.commands.progress import ProgressBar
from groundstation.errors import UserError

FORMATS = (".csv", ".parquet", ".xlsx")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="a recording (.gsrec) or a dataset CSV")
    parser.add_argument("--out", required=True, type=Path, metavar="OUT", help="OUT.csv, OUT.parquet or OUT.xlsx (by extension)")
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
    if args.out.exists() and not args.overwrite:
        raise UserError(f"{args.out} exists; choose another name or pass --overwrite")
    filters, overrides = estimator_options(args)
    bar = ProgressBar("decoding")
    data = load_session(args.file, filters, overrides, bar)
    bar.done()
    if suffix == ".xlsx":
        written = write_excel(args, data, overrides)
    else:
        columns = export_columns(data, select_rows(data.time_s, args.t_from, args.t_to, args.rate))
        (write_csv if suffix == ".csv" else write_parquet)(columns, args.out, args.overwrite)
        written = f"{len(columns['time_s'])} rows, {len(columns)} columns"
    for finding in data.damage:
        print(f"warning: {finding}")
    print(f"wrote {args.out}: {written}")
    return 0


def write_excel(args: argparse.Namespace, data, overrides: dict) -> str:
    from groundstation.export.excel import write_workbook

    bar = ProgressBar("writing")
    sheets = write_workbook(data, args.out, t_from=args.t_from, t_to=args.t_to, rate_hz=args.rate, forced=overrides,
                            overwrite=args.overwrite, progress=bar)
    bar.done()
    return f"sheets {', '.join(sheets)}"

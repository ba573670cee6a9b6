"""A folder of logs on the command line: ``evaluate DIR --out OUT`` and ``report DIR --out OUT``
(``groundstation.logbook``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.errors import UserError
from groundstation.text import clean


def add_folder_options(parser: argparse.ArgumentParser, out_help: str) -> None:
    parser.add_argument("--out", type=Path, metavar="OUT", help=f"for a FOLDER: {out_help}")
    parser.add_argument("--workers", type=int, metavar="N", help="for a FOLDER: processes at once (default: one per core)")
    parser.add_argument("--dask", metavar="SCHEDULER",
                        help="for a FOLDER: run the logs as tasks on this Dask scheduler (tcp://HOST:8786) instead")


def run_folder(args: argparse.Namespace, names, overrides, pages: bool) -> int:
    """Every log under the folder into one Parquet dataset (``pages``: and its flight reports with an
    index), a progress line per log; a log that cannot be read is said and has its error in its row, the
    batch goes on."""
    from groundstation.logbook.folder import evaluate_folder

    if args.out is None:
        raise UserError(f"{args.file} is a folder: say where its dataset goes with --out OUT")
    if overrides:
        raise UserError("--set applies to one file; a folder runs every estimator with its own settings")
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers must be at least 1, not {args.workers}")

    def progress(done: int, total: int, path: Path, rows: list[dict], seconds: float) -> None:
        error = rows[0].get("error")
        estimators = [row["estimator"] for row in rows if row["estimator"]]
        said = (f"error: {error}" if error else f"{len(estimators)} estimators against the {rows[0]['reference']}"
                if rows[0]["reference"] else f"{len(estimators)} estimators, nothing to compare them with")
        line = f"[{done}/{total}] {rows[0]['path']}: {said} ({seconds:.1f} s)"
        print(clean(line, visible=True), flush=True)  # a file's name, its error: one line, nothing acting on the terminal

    rows = evaluate_folder(args.file, args.out, names, args.workers, args.dask, progress, pages=pages)
    logs = {row["log_id"] for row in rows}
    failed = {row["log_id"] for row in rows if row["error"]}
    pages_said = f", reports/ and {Path(args.out) / 'index.html'} (worst first)" if pages else ""
    line = f"wrote {args.out}: logs.parquet ({len(rows)} rows, {len(logs)} logs, {len(failed)} unreadable), tables/{pages_said}"
    print(clean(line, visible=True))
    return 0

"""A folder of logs on the command line: ``evaluate DIR --out OUT`` and ``report DIR --out OUT``
(``groundstation.logbook``)."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.errors import UserError
from groundstation.text import clean


def add_folder_options(parser: argparse.ArgumentParser, out_help: str) -> None:
    parser.add_argument("--out", type=Path, metavar="OUT", help=f"for a FOLDER: {out_help}")
    parser.add_argument("--overwrite", action="store_true",
                        help="for a FOLDER: replace the dataset an earlier run wrote in OUT (default: OUT must be new or empty)")
    add_batch_options(parser)


def add_batch_options(parser: argparse.ArgumentParser) -> None:
    from groundstation.logbook import DEFAULT_LIMIT_S

    parser.add_argument("--workers", type=int, metavar="N",
                        help="for a FOLDER: processes at once (default: one per core; at most one per core and "
                             "per GB of free memory)")
    parser.add_argument("--time-limit", type=float, metavar="S",
                        help=f"for a FOLDER: seconds one log may take; its worker is then ended and the log reported "
                             f"(default: {DEFAULT_LIMIT_S:g})")
    parser.add_argument("--dask", metavar="SCHEDULER",
                        help="for a FOLDER: run the logs as tasks on this Dask scheduler (tcp://HOST:8786) instead")


def refuse_batch_options(args: argparse.Namespace) -> None:
    if args.workers is not None or args.dask is not None or args.time_limit is not None:
        raise UserError("--workers, --time-limit and --dask are for a folder of logs")


def run_folder(args: argparse.Namespace, names, overrides, pages: bool) -> int:
    """Every log under the folder into one Parquet dataset (``pages``: and its flight reports with an
    index), a progress line per log; a log that cannot be read is said and has its error in its row, the
    batch goes on."""
    from groundstation.logbook import DEFAULT_LIMIT_S
    from groundstation.logbook.folder import evaluate_folder, worker_count

    if args.out is None:
        raise UserError(f"{args.file} is a folder: say where its dataset goes with --out OUT")
    if overrides:
        raise UserError("--set applies to one file; a folder runs every estimator with its own settings")
    if args.workers is not None and args.workers < 1:
        raise UserError(f"--workers must be at least 1, not {args.workers}")
    if args.time_limit is not None and not args.time_limit > 0:
        raise UserError(f"--time-limit must be more than 0 s, not {args.time_limit:g}")
    if args.dask is not None and (args.workers is not None or args.time_limit is not None):
        raise UserError("--workers and --time-limit are for the local processes; a Dask cluster sets its own")
    workers, capped = worker_count(args.workers)
    if capped:
        print(capped, flush=True)

    def progress(done: int, total: int, path: Path, rows: list[dict], seconds: float) -> None:
        error = rows[0].get("error")
        estimators = [row["estimator"] for row in rows if row["estimator"]]
        said = (f"error: {error}" if error else f"{len(estimators)} estimators against the {rows[0]['reference']}"
                if rows[0]["reference"] else f"{len(estimators)} estimators, nothing to compare them with")
        line = f"[{done}/{total}] {rows[0]['path']}: {said} ({seconds:.1f} s)"
        print(clean(line, visible=True), flush=True)  # a file's name, its error: one line, nothing acting on the terminal

    limit_s = DEFAULT_LIMIT_S if args.time_limit is None else args.time_limit
    rows = evaluate_folder(args.file, args.out, names, workers, args.dask, progress, pages=pages, limit_s=limit_s,
                           overwrite=args.overwrite)
    logs = {row["log_id"] for row in rows}
    failed = {row["log_id"] for row in rows if row["error"]}
    pages_said = f", reports/ and {Path(args.out) / 'index.html'} (worst first)" if pages else ""
    line = f"wrote {args.out}: logs.parquet ({len(rows)} rows, {len(logs)} logs, {len(failed)} failed), tables/{pages_said}"
    print(clean(line, visible=True))
    return 0

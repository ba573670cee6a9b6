"""``groundstation report FILE --out report.html``: a flight report of any session file, one HTML page
that opens offline (``groundstation.export.report``): the flight, findings ranked by severity,
attitude, vibration, link, events and messages. What the file lost is printed first, as every
command does."""

from __future__ import annotations

import argparse
from pathlib import Path

from groundstation.commands.folder import add_batch_options, refuse_batch_options, run_folder
from groundstation.commands.options import add_estimator_options, estimator_options
from groundstation.text import clean


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats

    parser.add_argument("file", metavar="FILE", help=f"{formats.described()}; or a FOLDER of them (every one under it)")
    parser.add_argument("--out", required=True, type=Path, metavar="OUT",
                        help="OUT.html, the page to write; for a FOLDER, a folder: OUT/index.html (the logs worst "
                             "first), OUT/reports/ (a page per log), and the dataset evaluate DIR writes")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace OUT.html if it exists; for a FOLDER, the dataset an earlier run wrote in OUT")
    add_batch_options(parser)
    add_estimator_options(parser, None)


def run(args: argparse.Namespace) -> int:
    from groundstation.commands.progress import ProgressBar, say_compiling
    from groundstation.errors import UserError
    from groundstation.export.report import write_report
    from groundstation.export.request import check_destination
    from groundstation.session_makers.load import load_session

    filters, overrides = estimator_options(args)
    if Path(args.file).is_dir():
        return run_folder(args, filters, overrides, pages=True)
    refuse_batch_options(args)
    if args.out.suffix.lower() not in (".html", ".htm"):
        raise UserError(f"{args.out}: a report is an HTML page; name it .html")
    check_destination(args.out, args.overwrite)  # said before the long load: an existing OUT, a missing folder
    say_compiling(args.file, filters)
    progress = ProgressBar(f"computing {Path(args.file).name}")
    try:
        data = load_session(args.file, filters, overrides, progress, exact=True)
    finally:
        progress.done()
    for warning in data.warnings:
        print(f"warning: {clean(warning, visible=True)}")
    print(clean(f"wrote {write_report(data, args.out, Path(args.file).name, overwrite=True)}", visible=True))
    return 0

"""``groundstation export``: a session (a recording, a dataset CSV, a .tlog, .bin or .ulg) to any of
``export.request.FORMATS``.

Everything given is checked before the decoding starts (``groundstation.export.request``).
"""

from __future__ import annotations

import argparse
import functools
from pathlib import Path

from groundstation.commands.options import add_config_option, add_imu_option, add_estimator_options, estimator_options
from groundstation.commands.progress import StagedProgress, say_compiling
from groundstation.text import clean


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats
    from groundstation.export.request import FORMATS, either

    parser.add_argument("file", metavar="FILE", help=formats.described())
    parser.add_argument("--out", required=True, type=Path, metavar="OUT",
                        help=either(f"OUT{f.suffix} ({f.name})" for f in FORMATS.values()) + ", by its extension")
    add_estimator_options(parser, None)
    add_config_option(parser)
    add_imu_option(parser)
    parser.add_argument("--from", dest="t_from", type=float, metavar="S", help="first second to export")
    parser.add_argument("--to", dest="t_to", type=float, metavar="S", help="last second to export")
    every_row = either(f.name for f in FORMATS.values() if f.every_row)
    parser.add_argument("--rate", type=float, metavar="HZ", help="decimate to about HZ samples per second"
                        + (f" (not {every_row}: every row of every table at its own rate)" if every_row else ""))
    parser.add_argument("--overwrite", action="store_true", help="replace OUT if it exists")


def run(args: argparse.Namespace) -> int:
    from groundstation.export.request import export_request, run_export
    from groundstation.session_makers.load import load_session

    filters, overrides = estimator_options(args)
    request = export_request(args.file, args.out, filters=filters, overrides=overrides, t_from=args.t_from,
                             t_to=args.t_to, rate_hz=args.rate, overwrite=args.overwrite,
                             accept_config_changes=args.accept_config_changes)
    say_compiling(args.file, filters)
    progress = StagedProgress()
    try:
        result = run_export(request, functools.partial(load_session, imu=args.imu), progress)
    finally:
        progress.done()
    for warning in result.warnings:
        print(f"warning: {clean(warning, visible=True)}")
    print(clean(result.message, visible=True))
    return 0

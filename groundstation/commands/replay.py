"""``groundstation replay``: a file computed whole (a recording, a dataset CSV, a .tlog, .bin or .ulg),
then its totals; with ``--speed``, played back at that pace with a live one-line summary first."""

from __future__ import annotations

import argparse

from groundstation.commands.options import add_config_option, add_imu_option, add_estimator_options, estimator_options
from groundstation.text import clean


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats

    parser.add_argument("file", metavar="FILE", help=formats.described())
    parser.add_argument("--speed", type=float, default=None, metavar="X",
                        help="play it back at X times real time (0.25-64) with a live summary; default: the totals at once")
    add_estimator_options(parser, None)
    add_config_option(parser)
    add_imu_option(parser)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from groundstation.commands.progress import ProgressBar, say_compiling
    from groundstation.commands.summary import follow, totals_line
    from groundstation.errors import UserError
    from groundstation.session_makers.load import load_session
    from groundstation.session.playback import RevealSession, check_speed

    filters, overrides = estimator_options(args)
    try:
        paced = None if args.speed is None else check_speed(args.speed)
    except ValueError as error:
        raise UserError(str(error)) from None
    say_compiling(args.file, filters)
    progress = ProgressBar(f"computing {Path(args.file).name}")
    data = load_session(args.file, filters, overrides, progress, args.accept_config_changes, imu=args.imu)
    progress.done()
    for warning in data.warnings:
        print(f"warning: {clean(warning, visible=True)}")
    session = RevealSession(data, args.file, (filters, overrides), speed=paced or 1.0, position_s=0.0 if paced else float("inf"))
    if paced:
        with session:
            follow(session)
    print(totals_line(session))
    return 0

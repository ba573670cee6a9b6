"""``groundstation replay``: a recording through the decoder and estimators, with a live one-line summary."""

from __future__ import annotations

import argparse

from groundstation.commands.options import add_estimator_options, estimator_options


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="a recording (.gsrec)")
    parser.add_argument("--speed", type=float, default=None, metavar="X",
                        help="pace at X times real time (0.25-64); default: as fast as possible")
    add_estimator_options(parser, None)


def run(args: argparse.Namespace) -> int:
    from groundstation.commands.summary import follow, totals_line
    from groundstation.session.live import LiveSession
    from groundstation.session.replay import pipeline_for
    from groundstation.sources.replay import open_replay

    filters, overrides = estimator_options(args)
    source = open_replay(args.file, args.speed)  # the opener of open_source's recording specs
    for finding in source.recording.damage:
        print(f"warning: {finding}")
    session = LiveSession(source, pipeline_for(source.recording, filters, overrides), record=False)
    with session:
        follow(session)
    print(totals_line(session))
    return 0

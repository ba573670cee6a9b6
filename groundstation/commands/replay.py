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
    from groundstation.commands.summary import follow
    from groundstation.errors import UserError
    from groundstation.recording import open_recording
    from groundstation.session.live import LiveSession
    from groundstation.session.replay import pipeline_for
    from groundstation.sources import ReplaySource

    filters, overrides = estimator_options(args)
    recording = open_recording(args.file)
    for finding in recording.damage:
        print(f"warning: {finding}")
    if recording.chunk_count == 0:
        raise UserError(f"{args.file}: no link data to replay (an imported dataset? use export or evaluate)")
    try:
        source = ReplaySource(recording, args.speed)
    except ValueError as error:
        raise UserError(str(error)) from None
    session = LiveSession(source, record=False)
    session.pipeline = pipeline_for(recording, filters, overrides)  # the recorded estimators and settings
    with session:
        follow(session)
    stats = session.pipeline.decoder.stats
    print(f"{len(session.pipeline.imu)} IMU samples, {stats.frames} frames, {stats.frames_lost} lost, "
          f"{stats.crc_errors} CRC errors, {stats.bytes_skipped} bytes skipped")
    return 0

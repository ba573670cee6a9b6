"""``groundstation app``: the desktop window (live monitoring, replay, export).

Without a port or a file it opens on the built-in simulated bridge, as ``--demo`` does, so the
first command of the README shows a live flight on a machine with no hardware.
"""

from __future__ import annotations

import argparse

from groundstation.commands.options import add_imu_option
from groundstation.errors import UserError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats
    from groundstation.sources.spec import source_forms

    parser.add_argument("recording", nargs="?", metavar="FILE", help=f"open this file for replay: {formats.described()}")
    parser.add_argument("--demo", action="store_true",
                        help="stream from the built-in simulated radio bridge (also the default without --port or RECORDING)")
    parser.add_argument("--port", metavar="SPEC",
                        help=f"connect to this source: {source_forms()} (docs/sources.md)")
    parser.add_argument("--baud", type=int, default=None, metavar="N",
                        help="serial baud rate unless the spec gives ?baud= (default: 115200, or 57600 for mavlink:PORT)")
    add_imu_option(parser)  # the window's File > "Full-rate IMU" starts checked with --imu fast


def run(args: argparse.Namespace) -> int:
    if args.demo and (args.port or args.recording):
        raise UserError("--demo opens the simulated bridge; leave out --port and RECORDING, or --demo")
    if args.port:
        from groundstation.sources import parse_spec

        parse_spec(args.port)  # a garbled spec is said here (status 2); a port that fails to open, in the window
    from groundstation.session_makers.factory import Sessions
    from groundstation.ui.app import run as run_app  # Qt is imported only here

    return run_app(args.port, args.baud, args.recording, Sessions(imu=args.imu))

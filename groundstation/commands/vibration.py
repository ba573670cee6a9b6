"""``groundstation vibration``: the vibration view of any session (recording, dataset CSV, flight log).

Prints the spectra's source, the peaks (motor harmonics labelled), the levels (RMS above 5 Hz), the
log's clip counters and a notch suggestion in the autopilot's parameters; ``--json`` the same as one
object (``VibrationSummary.as_dict``). Everything is ``analysis.vibration.vibration_summary``'s.
``--what-if notch|lowpass`` adds what that filter would do (``analysis.whatif``), at ``--what-if-hz``
(default: the suggested notch's centre): the spectra before and after (attenuation at the peak), its phase
lag and gain (the Bode view), and the attitude difference where the estimators' IMU can carry it; only on
data sampled faster than twice its frequency. ``--imu fast`` opens a flight log on its full-rate IMU
(where it is bursts, the estimators stay on the logged IMU and a warning says so).
"""

from __future__ import annotations

import argparse
import json
import sys

from groundstation.errors import UserError
from groundstation.text import clean


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats
    from groundstation.commands.options import add_imu_option

    parser.add_argument("file", metavar="FILE", help=formats.described())
    parser.add_argument("--from", dest="t_from", type=float, metavar="S", help="first second (session time; default: the start)")
    parser.add_argument("--to", dest="t_to", type=float, metavar="S", help="last second (default: the end)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")
    add_imu_option(parser)
    parser.add_argument("--what-if", choices=("notch", "lowpass"),
                        help="filter the IMU (where sampled above twice the filter's frequency) and say what it changes")
    parser.add_argument("--what-if-hz", type=float, metavar="HZ", help="the filter's centre or cut-off (default: the suggested notch)")
    parser.add_argument("--what-if-bw", type=float, metavar="HZ", help="the notch's bandwidth (default: half its centre)")


def run(args: argparse.Namespace) -> int:
    from groundstation.analysis.vibration import VibrationError, vibration_summary
    from groundstation.commands.progress import ProgressBar
    from groundstation.session_makers.load import load_session

    if args.t_from is not None and args.t_to is not None and not args.t_from < args.t_to:
        raise UserError(f"--from ({args.t_from:g} s) must come before --to ({args.t_to:g} s)")
    bar = ProgressBar("reading")
    try:
        data = load_session(args.file, progress=bar, imu=args.imu)
    finally:
        bar.done()
    try:
        summary = vibration_summary(data, args.t_from, args.t_to)
        change = None
        if args.what_if:
            change = what_if_of(data, summary, args)
    except VibrationError as error:
        raise UserError(f"{args.file}: {error}") from None
    for warning in data.warnings:
        print(f"warning: {clean(warning, visible=True)}", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print(json.dumps({**summary.as_dict(), **({"what_if": change.as_dict()} if change else {})}, indent=2))
    else:
        print("\n".join(clean(line, visible=True) for line in summary.lines()))  # its tables' names: the log's
        if change:
            print("\n".join(change.lines()))
    return 0


def what_if_of(data, summary, args):
    from groundstation.analysis.whatif import what_if

    frequency_hz = args.what_if_hz if args.what_if_hz is not None else summary.notch.get("frequency_hz")
    if frequency_hz is None:
        raise UserError("no peak to place the filter at: give --what-if-hz")
    bandwidth_hz = args.what_if_bw if args.what_if_bw is not None else (
        summary.notch.get("bandwidth_hz") if args.what_if_hz is None else None)
    return what_if(data, args.what_if, frequency_hz, bandwidth_hz, summary.start_s, summary.end_s)

"""``groundstation bridge-sim``: the simulated aircraft on a pseudo-terminal, in real time.

The first line of stdout ends with the device path to open (any baud rate). Streams until SIGINT or
SIGTERM (or ``--duration``), answers uplink commands, then prints what the link injected to stderr.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import signal
import sys
import tempfile

from groundstation.errors import UserError
from groundstation.sim.options import add_scenario_arguments, scenario_from_args

# Without --duration the profile is made a day long; after it the craft holds still.
OPEN_ENDED_PROFILE_S = 86_400.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_scenario_arguments(parser)
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds (default: run until stopped)")
    parser.add_argument("--link", default=None, metavar="PATH",
                        help="also make PATH a symlink to the pty (kept across --dropout-every reconnections)")
    parser.add_argument("--firmware", choices=("python", "c"), default="python",
                        help="who runs the board: the Python model (default) or the reference firmware's C core, "
                             "built with the system C compiler (firmware in the loop; MPU-6050 only)")
    parser.add_argument("--timing-log", default=None, metavar="FILE",
                        help="append one line per write: host monotonic ns, then the device t_us of the frames written")


def run(args: argparse.Namespace) -> int:
    if os.name != "posix":
        raise UserError("bridge-sim needs a POSIX pseudo-terminal; on Windows the app offers the simulator in process")
    from firmware_protocol.reference.host import CoreUnavailable
    from groundstation.sim.pty_bridge import PtyBridge
    from groundstation.sim.stream import SimStream

    scenario = scenario_from_args(args, args.duration if args.duration is not None else OPEN_ENDED_PROFILE_S)
    scenario = dataclasses.replace(scenario, firmware_core=args.firmware)
    try:
        stream = SimStream(scenario)
    except (ValueError, CoreUnavailable) as error:
        raise UserError(f"--firmware {args.firmware}: {error}") from None
    link_path = args.link
    if link_path is None and scenario.link.dropout_every_s:
        # A pty that comes back is a new /dev/pts/N: readers need a name that survives it.
        link_path = os.path.join(tempfile.mkdtemp(prefix="groundstation-bridge-"), "ttySIM0")
    stopping = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stopping.append(True))
    log = open(args.timing_log, "a", encoding="ascii") if args.timing_log else None
    try:
        bridge = PtyBridge(stream, link_path, log)
    except OSError as error:
        raise UserError(f"cannot open a pseudo-terminal or the link {link_path}: {error}") from None
    s = scenario.firmware
    print(f"bridge-sim: '{scenario.profile}' seed {scenario.seed}, mode {s.mode}, {s.rate_hz} Hz, {args.firmware} firmware on {bridge.path}",
          flush=True)
    try:
        bridge.run(lambda: bool(stopping), args.duration)
    finally:
        bridge.close()
        if log is not None:
            log.close()
    report = bridge.stream.link.report
    print(f"bridge-sim: wrote {bridge.bytes_written} bytes ({bridge.bytes_dropped} dropped with no reader), "
          f"{bridge.reconnects} reconnections; link: {report.as_dict()}", file=sys.stderr)
    return 0

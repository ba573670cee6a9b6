"""``groundstation bridge-sim``: the simulated aircraft on a pseudo-terminal, in real time.

The first line of stdout ends with the device path to open (any baud rate). Streams until SIGINT or
SIGTERM (or ``--duration``), answers uplink commands, then prints what the link injected to stderr.
``--mavlink`` makes it an ArduPilot-like aircraft speaking MAVLink instead of this project's protocol
(``sim/mavlink_aircraft.py``); ``--udp HOST:PORT`` sends that MAVLink as UDP datagrams, as SITL does.
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
from groundstation.sim.settings import MAX_DURATION_S  # without --duration: a day; after it the craft holds still


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
    mav = parser.add_argument_group("MAVLink aircraft")
    mav.add_argument("--mavlink", action="store_true", help="speak MAVLink 2 as an ArduPilot copter (RAW_IMU/ATTITUDE at 4 Hz until asked for more)")
    mav.add_argument("--mavlink1", action="store_true", help="speak MAVLink 1 (implies --mavlink)")
    mav.add_argument("--udp", default=None, metavar="HOST:PORT", help="send the MAVLink over UDP to HOST:PORT instead of a pty (implies --mavlink)")


def run(args: argparse.Namespace) -> int:
    from groundstation.sim.stream import SimStream

    scenario = scenario_from_args(args, args.duration if args.duration is not None else MAX_DURATION_S)
    scenario = dataclasses.replace(scenario, firmware_core=args.firmware)
    mavlink = args.mavlink or args.mavlink1 or args.udp is not None
    if mavlink:
        from groundstation.sim.mavlink_aircraft import MavlinkAircraft

        if args.firmware != "python":
            raise UserError("--firmware c runs this project's firmware, which does not speak MAVLink")
        stream = MavlinkAircraft(scenario, mavlink1=args.mavlink1)
    else:
        from firmware_protocol.reference.host import CoreUnavailable

        try:
            stream = SimStream(scenario)
        except (ValueError, CoreUnavailable) as error:
            raise UserError(f"--firmware {args.firmware}: {error}") from None
    stopping = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stopping.append(True))
    if args.udp is not None:
        return run_udp(stream, args.udp, args.duration, stopping)
    if os.name != "posix":
        raise UserError("bridge-sim needs a POSIX pseudo-terminal; on Windows the app offers the simulator in process")
    from groundstation.sim.pty_bridge import PtyBridge

    link_path = args.link
    if link_path is None and scenario.link.dropout_every_s:
        # A pty that comes back is a new /dev/pts/N: readers need a name that survives it.
        link_path = os.path.join(tempfile.mkdtemp(prefix="groundstation-bridge-"), "ttySIM0")
    log = open(args.timing_log, "a", encoding="ascii") if args.timing_log else None
    try:
        bridge = PtyBridge(stream, link_path, log)
    except OSError as error:
        raise UserError(f"cannot open a pseudo-terminal or the link {link_path}: {error}") from None
    s = scenario.firmware
    what = "MAVLink" + (" 1" if args.mavlink1 else " 2") if mavlink else f"mode {s.mode}, {s.rate_hz} Hz, {args.firmware} firmware"
    print(f"bridge-sim: '{scenario.profile}' seed {scenario.seed}, {what} on {bridge.path}", flush=True)
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


def run_udp(stream, target: str, duration_s: float | None, stopping: list) -> int:
    from groundstation.sim.udp_bridge import UdpBridge

    host, _, port = target.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) <= 65535:
        raise UserError(f"--udp expects HOST:PORT with a port from 1 to 65535, e.g. 127.0.0.1:14550, not {target!r}")
    bridge = UdpBridge(stream, (host, int(port)))
    print(f"bridge-sim: '{stream.scenario.profile}' seed {stream.scenario.seed}, MAVLink on {bridge.path}", flush=True)
    try:
        bridge.run(lambda: bool(stopping), duration_s)
    finally:
        bridge.close()
    print(f"bridge-sim: sent {bridge.datagrams} datagrams, {bridge.bytes_written} bytes; "
          f"stream requests {stream.requests}, refused commands {stream.refused}", file=sys.stderr)
    return 0

"""``groundstation record``: a headless live session that records and prints link health.

For the field (a laptop by the runway, no window) and for tests. Runs until ``--duration`` or Ctrl-C
(SIGINT/SIGTERM), then closes the recording cleanly and says where it is. Exit status 0 when stopped
that way, 1 when the source failed for good or decoding stopped on an error (the recording keeps what
came before; the reason is printed) or the recording failed (a full disk: how many seconds were not
recorded is said), 2 for bad input.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import tempfile
import time
from pathlib import Path

from groundstation import stopwatch
from groundstation.commands.options import add_estimator_options, estimator_options
from groundstation.errors import UserError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation.estimation import live_estimators
    from groundstation.sources.spec import source_forms

    parser.add_argument("--port", required=True, metavar="SPEC",
                        help=f"the live source: {source_forms(but=('recording',))} (docs/sources.md)")
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S seconds (default: at Ctrl-C)")
    parser.add_argument("--baud", type=int, default=None, metavar="N",
                        help="serial baud rate unless the spec gives ?baud= (default: 115200, or 57600 for mavlink:PORT)")
    parser.add_argument("--recordings", type=Path, default=None, metavar="DIR",
                        help="record into DIR (default: $GROUNDSTATION_RECORDINGS or the platform's recordings folder)")
    parser.add_argument("--foxglove", metavar="[HOST:]PORT", default=None,
                        help="serve the live session to Foxglove (or any Foxglove WebSocket client) on PORT, "
                             "listening on 127.0.0.1 unless HOST is given (0.0.0.0: every interface); native apps "
                             "and web pages of this machine, Foxglove's and Lichtblick's web apps are served, other pages refused")
    parser.add_argument("--foxglove-native-only", action="store_true",
                        help="serve Foxglove's and Lichtblick's desktop apps only: refuse every web page")
    add_estimator_options(parser, ",".join(live_estimators()))


def run(args: argparse.Namespace) -> int:
    from groundstation.commands.summary import follow, totals_line
    from groundstation.export.foxglove_live import FoxgloveBridge, parse_address
    from groundstation.recording import default_recordings_dir
    from groundstation.session_makers.factory import open_session
    from groundstation.sources import parse_spec

    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise UserError(f"--duration must be a positive number of seconds, not {args.duration:g}")
    filters, overrides = estimator_options(args)
    if parse_spec(args.port).scheme == "recording":
        raise UserError(f"{args.port} is a recording already: 'groundstation replay {args.port}' plays it")
    folder = writable_folder(args.recordings or default_recordings_dir())
    bridge = (FoxgloveBridge(*parse_address(args.foxglove), web_apps=not args.foxglove_native_only)
              if args.foxglove is not None else None)
    try:
        session = open_session(args.port, filters=filters, settings=overrides, recordings_dir=folder,
                               **({"baud": args.baud} if args.baud else {}))
    except BaseException:
        if bridge is not None:
            bridge.close()
        raise
    print(f"recording {session.source.description} to {session.recording_path}", flush=True)
    if bridge is not None:
        bridge.serve(session)
        print(f"serving Foxglove on {bridge.address} (Foxglove: Open connection, Foxglove WebSocket)", flush=True)
    stopping: list[int] = []
    previous = {signum: signal.signal(signum, lambda signum, _: stopping.append(signum))
                for signum in (signal.SIGINT, signal.SIGTERM)}
    deadline = None if args.duration is None else time.monotonic() + args.duration
    first_data = first_data_stopwatch(session) if stopwatch.wanted() else lambda: None
    try:
        with session:
            follow(session, until=lambda: first_data() or bool(stopping) or (deadline is not None and time.monotonic() >= deadline))
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if bridge is not None:
            bridge.close()
            print(bridge.status_text(), flush=True)
    ended_ns = time.monotonic_ns()
    print(totals_line(session))
    for path in session.recorder.paths:
        size = path.stat().st_size if path.exists() else 0
        print(f"recording closed: {path} ({size / 1e6:.2f} MB)")
    status = 0
    with session.lock:
        unrecorded = unrecorded_stretches(session.pipeline.events, ended_ns)
    if unrecorded:
        lost_s = sum(seconds for _, seconds in unrecorded)
        print(f"groundstation record: the recording failed {len(unrecorded)} time(s) ({unrecorded[0][0]}): "
              f"{lost_s:.1f} s of the session were not recorded", file=sys.stderr)
        status = 1
    if session.error:
        print(f"groundstation record: the session stopped: {session.error}", file=sys.stderr)
        status = 1
    return status


def first_data_stopwatch(session):
    """For ``follow``'s ``until``: notes the first IMU sample with its estimates in the session's tables
    (``groundstation.stopwatch``: the CPU seconds, and which estimators were not compiled then), once."""
    noted = []

    def check() -> None:
        if not noted and len(session.view.imu):
            noted.append(stopwatch.note("first data"))
            stopwatch.note_uncompiled(session.view.uncompiled())

    return check


def unrecorded_stretches(events: list[dict], ended_ns: int) -> list[tuple[str, float]]:
    """(why, seconds) for each time the recording failed: until it resumed, or until the session ended."""
    out = []
    failed = None
    for event in events:
        if event["kind"] == "recording_failed":
            failed = event
        elif event["kind"] == "recording_resumed" and failed is not None:
            out.append((failed["message"], (event["t_host_ns"] - failed["t_host_ns"]) / 1e9))
            failed = None
    if failed is not None:
        out.append((failed["message"], max(0, ended_ns - failed["t_host_ns"]) / 1e9))
    return out


def writable_folder(folder: Path) -> Path:
    """``folder``, created if needed, once a file could be written there: a bad folder is said before
    the session starts, not after the first seconds of a flight."""
    folder = Path(folder).expanduser()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as error:
        raise UserError(f"cannot write recordings into {folder}: {error.strerror or error} "
                        "(choose another with --recordings DIR or GROUNDSTATION_RECORDINGS)") from None
    return folder

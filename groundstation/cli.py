"""The ``groundstation`` command: one subcommand per module, imported only when it runs.

Each command module provides ``add_arguments(parser)`` and ``run(args) -> int``. Keeping the
imports lazy keeps ``groundstation --help`` fast and keeps Qt out of every headless command.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from groundstation import __version__
from groundstation.errors import UserError
from groundstation.export.request import FORMATS as EXPORT_FORMATS, either
from groundstation.text import clean

FILES = "a recording, a dataset CSV, a .tlog, .bin or .ulg"  # what load_session opens (formats.FORMATS)
# name -> (module, one-line help: what the command takes and does). Later issues add their commands here.
COMMANDS: dict[str, tuple[str, str]] = {
    "app": ("groundstation.commands.app", f"the desktop app: a live source (--port; --demo, the default: the simulated bridge) or a file: {FILES}"),
    "protocol": ("groundstation.commands.protocol", "show the wire protocol or decode a raw byte file"),
    "evaluate": ("groundstation.commands.evaluate", f"score the attitude estimators on {FILES}: against its truth, else against the onboard estimate"),
    "bridge-sim": ("groundstation.commands.bridge_sim", "the simulated aircraft on a pseudo-terminal, streaming in real time"),
    "simulate": ("groundstation.commands.simulate", "write a simulated session (raw bytes + truth CSV) as fast as possible"),
    "ports": ("groundstation.commands.ports", "list the serial ports with description and VID:PID"),
    "replay": ("groundstation.commands.replay", f"compute {FILES} headless and print its totals (--speed: paced, with a live summary)"),
    "record": ("groundstation.commands.record", "record a live source headless (--port SPEC), printing link health"),
    "import": ("groundstation.commands.import_csv", "turn a dataset CSV (raw IMU layout, plain or .gz) into a recording"),
    "export": ("groundstation.commands.export", f"export {FILES} to {either(f.name for f in EXPORT_FORMATS.values())}"),
    "vibration": ("groundstation.commands.vibration", f"vibration spectra, peaks, levels, clipping and a notch suggestion of {FILES}"),
    "report": ("groundstation.commands.report", f"a flight report of {FILES}: one HTML page that opens offline"),
    "experiments": ("groundstation.commands.experiments", "the seed papers' experiments on the simulator: tables and PNG figures"),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="groundstation",
        description="Ground station for small quadrotors (MPU-6050 + nRF24L01 telemetry).",
    )
    parser.add_argument("--version", action="version", version=f"groundstation {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module_name, help_text) in COMMANDS.items():
        # add_help=False: '--help' after a command reaches that command's own parser.
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    top, rest = parser.parse_known_args(argv)
    if top.command is None:
        top.command = "app"  # plain 'groundstation' is the app (on the simulated bridge unless told otherwise)
    module_name, help_text = COMMANDS[top.command]
    module = importlib.import_module(module_name)
    command_parser = argparse.ArgumentParser(prog=f"groundstation {top.command}", description=help_text)
    module.add_arguments(command_parser)
    args = command_parser.parse_args(rest)
    try:
        return int(module.run(args) or 0)
    except UserError as error:
        print(f"groundstation {top.command}: {clean(str(error), visible=True)}", file=sys.stderr)  # names in it: one line
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        # The reader of our output went away (``| head``): not an error of ours. Python would report
        # the failed flush of stdout at exit; point it at /dev/null instead. 141 is what a shell
        # reports for a command killed by SIGPIPE.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141

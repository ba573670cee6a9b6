"""``groundstation app``: the desktop window (live monitoring, replay, export)."""

from __future__ import annotations

import argparse

from groundstation.errors import UserError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--demo", action="store_true", help="stream from the built-in simulated radio bridge")


def run(args: argparse.Namespace) -> int:
    raise UserError("the desktop app is not built yet; 'groundstation --help' lists what exists")

"""``groundstation ports``: the serial ports on this machine, with description and VID:PID."""

from __future__ import annotations

import argparse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    pass


def run(args: argparse.Namespace) -> int:
    from groundstation.sources import list_ports

    ports = list_ports()
    if not ports:
        print("no serial ports found (is the USB radio bridge plugged in?)")
    for port in ports:
        print(f"{port['device']:<20} {port['vid_pid']:<10} {port['description']}")
    return 0

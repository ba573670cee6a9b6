"""``groundstation report FILE --out report.html``: a flight report (``groundstation.report``)."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats

    parser.add_argument("file", metavar="FILE", help=formats.described())
    parser.add_argument("--out", required=True, type=Path, metavar="OUT.html", help="the HTML page to write")


def run(args: argparse.Namespace) -> int:
    raise NotImplementedError

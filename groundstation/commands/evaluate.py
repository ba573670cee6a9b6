"""``groundstation evaluate``: inclination accuracy of the estimators on a file with truth.

The file is a recording with truth (a simulated flight, an imported dataset trial) or a dataset CSV
(plain or .gz; ../shared/datasets/README.md); an imported trial scores exactly as its CSV. Output: a table, or with ``--json`` an object mapping each estimator
name to ``{"incl_rmse_deg": ..., "incl_max_deg": ...}``.
"""

from __future__ import annotations

import argparse
import json

from groundstation.commands.options import add_estimator_options, estimator_options


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="a recording (.gsrec) with truth, or a dataset CSV (.csv or .csv.gz)")
    from groundstation.estimation import ESTIMATORS, GPS_AIDED

    # The GPS-aided filters are left out by default: the datasets have no GPS, and without it they are
    # slow tilt filters at ~100x the others' cost. --filters ukf,sssrukf scores them.
    add_estimator_options(parser, ",".join(name for name in ESTIMATORS if name not in GPS_AIDED))
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    from groundstation.session.data import load_session

    names, overrides = estimator_options(args)
    results = load_session(args.file, names, overrides).evaluate()
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        print(f"{'estimator':<10} {'incl RMSE (deg)':>16} {'incl max (deg)':>15}")
        for name, figures in results.items():
            print(f"{name:<10} {figures['incl_rmse_deg']:>16.3f} {figures['incl_max_deg']:>15.3f}")
    return 0

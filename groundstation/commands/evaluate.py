"""``groundstation evaluate``: inclination accuracy of the estimators on a file with truth.

The file is a recording with truth (a simulated flight, an imported dataset trial) or a dataset CSV
(plain or .gz; ../shared/datasets/README.md); an imported trial scores exactly as its CSV. Output: a table, or with ``--json`` an object mapping each estimator
name to ``{"incl_rmse_deg": ..., "incl_max_deg": ...}``.
"""

from __future__ import annotations

import argparse
import json

from groundstation.errors import UserError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", metavar="FILE", help="a recording (.gsrec) with truth, or a dataset CSV (.csv or .csv.gz)")
    parser.add_argument("--filters", default="ahf,hf,ecf,cf1,kf,ekf", help="comma-separated estimators (default: all)")
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="NAME.PARAM=VALUE",
        help="override an estimator setting, e.g. hf.beta=0.033 (repeatable)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    # Imported here so that 'groundstation evaluate --help' stays fast.
    from groundstation.estimation import create, parse_overrides
    from groundstation.session.data import load_session

    names = [n.strip() for n in args.filters.split(",") if n.strip()]
    try:
        overrides = parse_overrides(args.overrides)
        for name in set(names) | set(overrides):
            create(name, overrides.get(name))  # validates names and parameters before the long run
        unused = set(overrides) - set(names)
        if unused:
            raise ValueError(f"--set names {', '.join(sorted(unused))}, which is not in --filters")
    except ValueError as error:
        raise UserError(str(error)) from None
    results = load_session(args.file, names, overrides).evaluate()
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        print(f"{'estimator':<10} {'incl RMSE (deg)':>16} {'incl max (deg)':>15}")
        for name, figures in results.items():
            print(f"{name:<10} {figures['incl_rmse_deg']:>16.3f} {figures['incl_max_deg']:>15.3f}")
    return 0

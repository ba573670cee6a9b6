"""``groundstation evaluate``: inclination accuracy of the estimators on a file with truth, or their
agreement with the aircraft's own estimate when there is no truth.

The file is a recording with truth (a simulated flight, an imported dataset trial), a dataset CSV
(plain or .gz; ../shared/datasets/README.md), or an autopilot's flight log (.tlog, .bin, .ulg); an
imported trial scores exactly as its CSV. With truth the output is a table, or with ``--json`` an
object mapping each estimator name to ``{"incl_rmse_deg": ..., "incl_max_deg": ...}``, with
``"heading_rmse_deg"`` and ``"heading_max_deg"`` too for the estimators that use the magnetometer when
the file has one (heading error after removing one constant offset: estimation/evaluation.py). Without truth but
with an onboard estimate (a flight log), it is each estimator's pitch/roll difference from that
estimate, labelled as agreement (the onboard estimate is not truth); ``--json`` gives
``{"agreement_with_onboard": {name: {"pitch_rms_deg", "pitch_max_deg", "roll_rms_deg", "roll_max_deg", "rows"}}}``.
What the file lost and the session's warnings (``SessionData.warnings``: damage, a cut log, an IMU too
slow to filter) are printed first, and ``--json`` carries them under ``"warnings"`` when there are any.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from groundstation.commands.folder import add_folder_options, refuse_batch_options, run_folder
from groundstation.commands.options import add_config_option, add_imu_option, add_estimator_options, estimator_options
from groundstation.errors import UserError
from groundstation.text import clean

AGREEMENT_TITLE = "agreement with the onboard estimate (difference, not error: the onboard estimate is not truth)"


def default_filters() -> str:
    """The estimators whose needs a file meets (the GPS-aided filters are left out: the datasets have no
    GPS, and without it they are slow tilt filters whose heading can flip). --filters ukf,sssrukf scores them."""
    from groundstation import formats
    from groundstation.estimation import runnable

    return ",".join(runnable(formats.FILE_AIDING))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from groundstation import formats

    parser.add_argument("file", metavar="FILE", help=f"a file with truth or an onboard estimate: {formats.described()}; "
                                                     "or a FOLDER of them (every one under it, with --out)")
    add_estimator_options(parser, default_filters())
    add_config_option(parser)
    add_imu_option(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_folder_options(parser, "the Parquet dataset to write (OUT/logs.parquet, a row per log and estimator; "
                               "OUT/tables/<table>/log_id=<id>/, each log's tables)")


def run(args: argparse.Namespace) -> int:
    from groundstation.autopilot.agreement import onboard_agreement
    from groundstation.commands.progress import ProgressBar, say_compiling
    from groundstation.estimation import unmet_warnings
    from groundstation.session_makers.load import load_session

    names, overrides = estimator_options(args)
    if Path(args.file).is_dir():
        return run_folder(args, names, overrides, pages=False)
    if args.out is not None or args.overwrite:
        raise UserError("--out and --overwrite are for a folder of logs; one file prints its figures")
    refuse_batch_options(args)
    say_compiling(args.file, names)
    bar = ProgressBar("computing")  # shown after a second: a long recording or log
    try:
        # exact: its figures are the estimates' own (``evaluate_trial``'s numbers), not those of the form sized for showing
        data = load_session(args.file, names, overrides, bar, args.accept_config_changes, imu=args.imu, exact=True)
    finally:
        bar.done()
    # an estimator asked for by name whose aiding the file lacks (ukf without GPS) is scored, and said to be so
    asked = data.estimated if args.filters != default_filters() else ()
    warnings = [*data.warnings, *unmet_warnings(asked, data.aiding(), args.file)]
    for warning in warnings:  # on stderr beside the JSON, and in it
        print(f"warning: {clean(warning, visible=True)}", file=sys.stderr if args.json else sys.stdout)
    carried = {"warnings": warnings} if warnings else {}
    if data.true_q is None and data.has_onboard():
        if not data.estimated:
            raise UserError(f"{args.file}: no IMU samples, so no host estimator ran; only the onboard estimate is there")
        return print_agreement(onboard_agreement(data), carried, args.json)
    results = data.evaluate()
    if args.json:
        print(json.dumps({**results, **carried}, indent=2))
    else:
        print(f"{'estimator':<10} {'incl RMSE (deg)':>16} {'incl max (deg)':>15} {'heading RMSE (deg)':>19} {'heading max (deg)':>18}")
        for name, f in results.items():
            heading = f"{f['heading_rmse_deg']:>19.3f} {f['heading_max_deg']:>18.3f}" if "heading_rmse_deg" in f else f"{'-':>19} {'-':>18}"
            print(f"{name:<10} {f['incl_rmse_deg']:>16.3f} {f['incl_max_deg']:>15.3f} {heading}")
    return 0


def print_agreement(results: dict, carried: dict, as_json: bool) -> int:
    if as_json:
        print(json.dumps({"agreement_with_onboard": results, **carried}, indent=2))
        return 0
    print(AGREEMENT_TITLE)
    print(f"{'estimator':<10} {'pitch RMS (deg)':>16} {'pitch max (deg)':>16} {'roll RMS (deg)':>15} {'roll max (deg)':>15}")
    for name, f in results.items():
        print(f"{name:<10} {f['pitch_rms_deg']:>16.3f} {f['pitch_max_deg']:>16.3f} {f['roll_rms_deg']:>15.3f} {f['roll_max_deg']:>15.3f}")
    return 0


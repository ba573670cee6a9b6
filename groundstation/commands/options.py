"""Options shared by the commands that run estimators: ``--filters``, the what-if ``--set``, ``--imu``."""

from __future__ import annotations

import argparse

from groundstation.errors import UserError


def add_estimator_options(parser: argparse.ArgumentParser, default_filters: str | None) -> None:
    from groundstation.estimation import ESTIMATORS

    help_filters = f"comma-separated estimators: {', '.join(ESTIMATORS)}"
    help_filters += f" (default: {default_filters})" if default_filters else " (default: those recorded)"
    parser.add_argument("--filters", default=default_filters, help=help_filters)
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="NAME.PARAM=VALUE",
        help="re-run an estimator with another setting, e.g. hf.beta=0.033 (repeatable)",
    )


def add_config_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--accept-config-changes", action="store_true",
                        help="apply a recording's CONFIG that changes the sensor's full scales or mounting without a "
                             "device restart (default: keep the scales in use, and say so)")


def add_imu_option(parser: argparse.ArgumentParser) -> None:
    from groundstation.formats import IMU_STREAMS

    parser.add_argument("--imu", choices=IMU_STREAMS, default=IMU_STREAMS[0],
                        help="the IMU stream a flight log's estimators run on: its logged IMU (default), or 'fast': the "
                             "full-rate one of ArduPilot's batch sampler (ISBH/ISBD) or PX4's sensor_gyro_fifo")


def estimator_options(args: argparse.Namespace) -> tuple[list[str] | None, dict[str, dict[str, float]]]:
    """``(filters or None, overrides)``, checked before any long run; UserError says what is wrong."""
    from groundstation.estimation import ESTIMATORS, create, parse_overrides

    names = None if args.filters is None else [n.strip() for n in args.filters.split(",") if n.strip()]
    if names == []:
        raise UserError(f"--filters names no estimator: give one or more of {', '.join(ESTIMATORS)}")
    try:
        overrides = parse_overrides(args.overrides)
        for name in set(names or []) | set(overrides):
            create(name, overrides.get(name), compile=False)  # checked, not compiled: numba takes seconds at a first start
        if names is not None and set(overrides) - set(names):
            raise ValueError(f"--set names {', '.join(sorted(set(overrides) - set(names)))}, which is not in --filters")
    except ValueError as error:
        raise UserError(str(error)) from None
    return names, overrides

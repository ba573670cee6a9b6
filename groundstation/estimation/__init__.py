"""Attitude estimators behind one interface (see ``base``), by the names used everywhere.

``ahf`` adaptive hybrid filter (seed 000, the paper's constants), ``ahf2`` its adaptive idea with gyro bias, rest detection
and a low-passed accelerometer (``ahf2.py``), ``hf`` the same with λ fixed (Madgwick IMU), ``ecf`` Mahony's
explicit complementary filter, ``cf1`` first-order complementary filter, ``kf`` per-axis Kalman filter,
``ekf`` quaternion extended Kalman filter, ``ukf`` and ``sssrukf`` the GPS-aided unscented filters of seed 001
(standard, and square-root with spherical simplex sigma points); with the magnetometer ``hfm`` (Madgwick MARG) and
``ecfm`` (Mahony ECF with the field error term), see ``marg``; ``mcf`` seed 003's multi-sensor complementary filter; ``vqf`` Laidig & Seel's VQF (the ``vqf`` package). ``create("hf", {"beta": 0.033})`` builds one with overrides.
"""

from __future__ import annotations

import dataclasses
import math

from groundstation.estimation.ahf import Ahf, Hf
from groundstation.estimation.ahf2 import Ahf2, Ahf2m
from groundstation.estimation.base import Estimator
from groundstation.estimation.cf1 import Cf1
from groundstation.estimation.ecf import Ecf
from groundstation.estimation.ekf import Ekf
from groundstation.estimation.kf import Kf
from groundstation.estimation.marg import Ecfm, Hfm
from groundstation.estimation.mcf import Mcf
from groundstation.estimation.ukf import Sssrukf, Ukf
from groundstation.estimation.vqf import Vqf

ESTIMATORS: dict[str, type[Estimator]] = {cls.name: cls for cls in (Ahf, Ahf2, Hf, Ecf, Cf1, Kf, Ekf, Vqf, Ukf, Sssrukf, Hfm, Ecfm, Mcf, Ahf2m)}
GPS_AIDED = ("ukf", "sssrukf")  # need GPS velocity and heading to be more than slow tilt filters


def setting_names(name: str) -> frozenset[str]:
    """The settings an estimator has (none for a name that is not an estimator)."""
    cls = ESTIMATORS.get(name)
    return frozenset(f.name for f in dataclasses.fields(cls.Settings)) if cls else frozenset()


def create(name: str, overrides: dict[str, float] | None = None) -> Estimator:
    """An estimator by name with some settings replaced; ValueError names what is wrong."""
    try:
        cls = ESTIMATORS[name]
    except KeyError:
        raise ValueError(f"unknown estimator {name!r}; choose from {', '.join(ESTIMATORS)}") from None
    defaults = dataclasses.asdict(cls.Settings())
    for param, value in (overrides or {}).items():
        if param not in defaults:
            raise ValueError(f"{name} has no setting {param!r}; its settings: {', '.join(sorted(defaults))}")
        # inf can be meant ("no limit"); NaN only where the default is NaN ("from the data", e.g. mcf's dip)
        if math.isnan(value) and not math.isnan(defaults[param]):
            raise ValueError(f"{name}.{param} must be a number, not NaN")
    return cls(dataclasses.replace(cls.Settings(), **(overrides or {})))


def parse_overrides(items: list[str]) -> dict[str, dict[str, float]]:
    """``["hf.beta=0.033", ...]`` -> ``{"hf": {"beta": 0.033}}``; ValueError on a malformed item."""
    result: dict[str, dict[str, float]] = {}
    for item in items:
        target, sep, value = item.partition("=")
        name, dot, param = target.strip().partition(".")
        if not sep or not dot or not name or not param:
            raise ValueError(f"--set expects NAME.PARAM=VALUE (e.g. hf.beta=0.033), got {item!r}")
        try:
            number = float(value)
        except ValueError:
            raise ValueError(f"--set {target}: {value!r} is not a number") from None
        result.setdefault(name, {})[param] = number
    return result

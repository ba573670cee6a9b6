"""Attitude estimators behind one interface (see ``base``), by the names used everywhere.

``ahf`` adaptive hybrid filter (seed 000, the paper's constants), ``ahf2`` its adaptive idea with gyro bias, rest detection
and a low-passed accelerometer (``ahf2.py``), ``hf`` the same with λ fixed (Madgwick IMU), ``ecf`` Mahony's
explicit complementary filter, ``cf1`` first-order complementary filter, ``kf`` per-axis Kalman filter,
``ekf`` quaternion extended Kalman filter, ``ukf`` and ``sssrukf`` the GPS-aided unscented filters of seed 001
(standard, and square-root with spherical simplex sigma points); with the magnetometer ``hfm`` (Madgwick MARG) and
``ecfm`` (Mahony ECF with the field error term), see ``marg``; ``mcf`` seed 003's multi-sensor complementary filter; ``vqf`` Laidig & Seel's VQF (the ``vqf`` package). ``create("hf", {"beta": 0.033})`` builds one with overrides.

``ESTIMATORS`` is the registry the app, the commands, the exports and the tests take their lists from;
``runnable`` picks those whose needs a session meets, ``aiding_estimator`` the one the compass heading
and the position use.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from collections.abc import Iterator, MutableMapping
from typing import TYPE_CHECKING

from groundstation.estimation.compiled_cache import use_user_cache

if TYPE_CHECKING:
    from groundstation.estimation.base import Estimator

use_user_cache()  # before any estimator imports numba: their compiled kernels survive a re-install

# Each built-in estimator's class by module and name, imported when first asked for: its module imports
# numba (seconds), which ``--help`` and the window's first frame need not wait for (bench/bench_help.py).
_BUILT_IN = {
    "Ahf2": "ahf2", "Vqf": "vqf", "Ahf": "ahf", "Hf": "ahf", "Ecf": "ecf", "Hfm": "marg", "Ecfm": "marg",
    "Mcf": "mcf", "Ukf": "ukf", "Sssrukf": "ukf", "Cf1": "cf1", "Kf": "kf", "Ekf": "ekf", "Ahf2m": "ahf2",
}


def _built_in(class_name: str) -> type:
    return getattr(importlib.import_module(f"groundstation.estimation.{_BUILT_IN[class_name]}"), class_name)


class _Registry(MutableMapping):
    """name -> estimator class; the names (keys, ``in``, ``len``) without importing any estimator, a
    class imported when it is looked up."""

    def __init__(self, entries: dict[str, str | type]):
        self._entries = entries  # name -> class, or the class's name in ``_BUILT_IN`` until first looked up

    def __getitem__(self, name: str) -> type:
        entry = self._entries[name]
        if isinstance(entry, str):
            entry = self._entries[name] = _built_in(entry)
        return entry

    def __setitem__(self, name: str, cls: type) -> None:
        self._entries[name] = cls

    def __delitem__(self, name: str) -> None:
        del self._entries[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)


# The one list of estimators, in the order the app, evaluate and exports show them: each class says its
# label, colour, needs and whether live sessions run it (``base.Estimator``). A new estimator is its
# module, its class's module in ``_BUILT_IN`` and its name added here (or ``register(cls)``); nothing else
# names it (tests/test_cli.py checks each name is its class's ``name``).
ESTIMATORS: MutableMapping[str, type[Estimator]] = _Registry({
    "ahf2": "Ahf2", "vqf": "Vqf", "ahf": "Ahf", "hf": "Hf", "ecf": "Ecf", "hfm": "Hfm", "ecfm": "Ecfm", "mcf": "Mcf",
    "ukf": "Ukf", "sssrukf": "Sssrukf", "cf1": "Cf1", "kf": "Kf", "ekf": "Ekf", "ahf2m": "Ahf2m",
})


def __getattr__(name: str):
    """``from groundstation.estimation import Hf`` (and ``Estimator``), imported on first use."""
    if name in _BUILT_IN:
        return _built_in(name)
    if name == "Estimator":
        return importlib.import_module("groundstation.estimation.base").Estimator
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# The estimator whose attitude turns the magnetometer into a compass heading and the acceleration
# into position (seed 004), unless a session names another (``Pipeline(aiding=...)``).
AIDING_ESTIMATOR = "ahf2"


def register(cls: type[Estimator]) -> type[Estimator]:
    """Add an estimator to ``ESTIMATORS`` (usable as a class decorator)."""
    ESTIMATORS[cls.name] = cls
    return cls


def label(name: str) -> str:
    """What the app and the exports call an estimator (its name if it is none of ours)."""
    cls = ESTIMATORS.get(name)
    return cls.label if cls else name


def live_estimators() -> tuple[str, ...]:
    """The estimators every live session runs (and so its recording's replays), so showing one is a
    legend click or a check box, not a restart: the IMU filters, those with the magnetometer and the
    GPS-aided unscented filters (a few µs per sample each, compiled; bench/bench_estimator_costs.out.md). Hidden curves cost the UI nothing per frame."""
    return tuple(name for name, cls in ESTIMATORS.items() if cls.live)


def runnable(capabilities, names=None) -> tuple[str, ...]:
    """Those of ``names`` (default: every estimator) whose needs ``capabilities`` ("mag", "gps") meet."""
    return tuple(n for n in (ESTIMATORS if names is None else names) if n in ESTIMATORS and ESTIMATORS[n].needs <= set(capabilities))


def aiding_estimator(filters, named: str | None = None) -> str | None:
    """The estimator that aids the compass heading and position among ``filters``: ``named`` if given
    (ValueError if it does not run), else ``AIDING_ESTIMATOR``; a session without that one is aided by
    the first it runs, as every session was before the role had a name (so older recordings replay
    the same). None without estimators."""
    if named is not None:
        if named not in filters:
            raise ValueError(f"the aiding estimator {named!r} is not among the session's ({', '.join(filters)})")
        return named
    if AIDING_ESTIMATOR in filters:
        return AIDING_ESTIMATOR
    return filters[0] if filters else None


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

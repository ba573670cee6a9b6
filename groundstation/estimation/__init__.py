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

from groundstation.palette import PALETTE, UNNAMED_COLOUR
from groundstation.estimation.compiled_cache import use_user_cache_for_numba

if TYPE_CHECKING:
    from groundstation.estimation.base import Estimator

use_user_cache_for_numba()  # as any estimator imports numba: their compiled kernels survive a re-install

@dataclasses.dataclass(frozen=True)
class About:
    """What the app, the commands and the exports say of a built-in estimator, known without importing its
    module (which imports numba: seconds, which ``--help`` and the window's first paint need not wait for;
    bench/bench_help.py, bench/bench_first_frame.py). Its class takes these facts from here
    (``base.Estimator.__init_subclass__``), so each is written once."""

    module: str  # groundstation.estimation.<module> defines the class
    class_name: str
    label: str  # what the legend, the panel and the charts call it
    colour: str  # a colour's name in the app's palette (``groundstation.palette.PALETTE``): Qt stays out of here
    needs: frozenset[str] = frozenset()  # aiding it is no more than a tilt filter without: "mag", "gps"
    live: bool = True  # run on every live session (so showing it is a click, not a restart)
    tunable: tuple[tuple[str, str, str], ...] = ()  # settings the app offers to tune live: (setting, symbol, unit)


_MAG, _GPS = frozenset({"mag"}), frozenset({"gps"})
_BETA = (("beta", "β", "rad/s"),)
_KP_KI = (("kp", "Kp", "rad/s"), ("ki", "Ki", "rad/s²"))
# The built-in estimators, in the order the app, evaluate and exports show them. CF1, KF and EKF only
# replays of older recordings have; AHF2+mag is for evaluate and replays (live sessions have hfm, ecfm,
# mcf and vqf for the heading); without GPS velocity the unscented filters are slow tilt filters at
# ~100x the others' cost.
BUILT_IN: dict[str, About] = {
    "ahf2": About("ahf2", "Ahf2", "AHF2", "black"),
    "vqf": About("vqf", "Vqf", "VQF", "orange"),
    "ahf": About("ahf", "Ahf", "AHF", "indigo", tunable=(("lambda_min", "λ min", "rad/s"), ("lambda_max", "λ max", "rad/s"))),
    "hf": About("ahf", "Hf", "HF", "green", tunable=_BETA),
    "ecf": About("ecf", "Ecf", "ECF", "teal", tunable=_KP_KI),
    "hfm": About("marg", "Hfm", "HF+mag", "olive", _MAG, tunable=_BETA),
    "ecfm": About("marg", "Ecfm", "ECF+mag", "cyan", _MAG, tunable=_KP_KI),
    "mcf": About("mcf", "Mcf", "MCF", "sand", _MAG),
    "ukf": About("ukf", "Ukf", "UKF", "rose", _GPS),
    "sssrukf": About("ukf", "Sssrukf", "SSSRUKF", "purple", _GPS),
    "cf1": About("cf1", "Cf1", "CF1", "olive", live=False),
    "kf": About("kf", "Kf", "KF", "cyan", live=False),
    "ekf": About("ekf", "Ekf", "EKF", "sand", live=False),
    "ahf2m": About("ahf2", "Ahf2m", "AHF2+mag", "purple", _MAG, live=False),
}
_BY_CLASS = {about.class_name: about for about in BUILT_IN.values()}


def _built_in(class_name: str) -> type:
    return getattr(importlib.import_module(f"groundstation.estimation.{_BY_CLASS[class_name].module}"), class_name)


class _Registry(MutableMapping):
    """name -> estimator class; the names (keys, ``in``, ``len``) and ``about`` without importing any
    estimator, a class imported when it is looked up."""

    def __init__(self, entries: dict[str, str | type]):
        self._entries = entries  # name -> class, or the class's name in ``BUILT_IN`` until first looked up

    def __getitem__(self, name: str) -> type:
        entry = self._entries[name]
        if isinstance(entry, str):
            entry = self._entries[name] = _built_in(entry)
        return entry

    def __setitem__(self, name: str, cls: type) -> None:
        self._entries[name] = cls

    def __delitem__(self, name: str) -> None:
        del self._entries[name]

    def __contains__(self, name) -> bool:  # the mixin's would look the class up, importing it
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def about(self, name: str) -> About:
        """An estimator's facts (KeyError for an unknown name): a built-in one's from ``BUILT_IN``, a
        registered class's from its attributes."""
        entry, facts = self._entries[name], BUILT_IN.get(name)
        if isinstance(entry, str) or (facts is not None and entry.__name__ == facts.class_name):
            return facts
        return About(entry.__module__, entry.__name__, entry.label, entry.colour, entry.needs, entry.live, entry.tunable)


def colour_of(name: str) -> str:
    """An estimator's colour as the app's plots and the report draw it (``groundstation.palette``; grey if it
    names none of the palette's)."""
    facts = about(name)
    return PALETTE.get(facts.colour, UNNAMED_COLOUR) if facts else UNNAMED_COLOUR


# The one list of estimators: each name's class and facts (``About``). A new estimator is its module and
# its entry in ``BUILT_IN`` (or ``register(cls)``); nothing else names it (tests/test_cli.py checks each
# name is its class's ``name``).
ESTIMATORS: MutableMapping[str, type[Estimator]] = _Registry({name: about.class_name for name, about in BUILT_IN.items()})


def about(name: str) -> About | None:
    """An estimator's facts without importing its kernels; None for a name that is not an estimator."""
    return ESTIMATORS.about(name) if name in ESTIMATORS else None


def __getattr__(name: str):
    """``from groundstation.estimation import Hf`` (and ``Estimator``), imported on first use."""
    if name in _BY_CLASS:
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
    facts = about(name)
    return facts.label if facts else name


def live_estimators() -> tuple[str, ...]:
    """The estimators every live session runs (and so its recording's replays), so showing one is a
    legend click or a check box, not a restart: the IMU filters, those with the magnetometer and the
    GPS-aided unscented filters (a few µs per sample each, compiled; bench/bench_estimator_costs.out.md). Hidden curves cost the UI nothing per frame."""
    return tuple(name for name in ESTIMATORS if ESTIMATORS.about(name).live)


def runnable(capabilities, names=None) -> tuple[str, ...]:
    """Those of ``names`` (default: every estimator) whose needs ``capabilities`` ("mag", "gps") meet."""
    return tuple(n for n in (ESTIMATORS if names is None else names) if n in ESTIMATORS and ESTIMATORS.about(n).needs <= set(capabilities))


# What an estimator is without an aiding it needs, for the one line that says so (``unmet_needs``)
_WITHOUT = {
    "gps": "GPS velocity and heading: without them it is a slow tilt filter whose heading drifts and can flip",
    "mag": "a magnetometer: without one its heading is the gyro's and drifts",
}


def unmet_needs(name: str, capabilities) -> str | None:
    """Why ``name`` is little use with only ``capabilities`` ("mag", "gps"), in one line; None when they meet its needs."""
    missing = sorted(ESTIMATORS.about(name).needs - set(capabilities)) if name in ESTIMATORS else []
    return "; ".join(f"{name} needs {_WITHOUT[need]}" for need in missing) or None


def unmet_warnings(names, capabilities, source) -> list[str]:
    """What evaluate and export say of the estimators of ``names`` asked for on ``source``, whose aiding
    it lacks (``unmet_needs``): one line each."""
    return [f"{why}, and {source} has none" for name in names if (why := unmet_needs(name, capabilities))]


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


_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


def settings_as_json(settings: dict[str, float | bool]) -> dict[str, float | bool | str]:
    """Settings for a JSON file (a recording's header and its settings events): JSON has no infinity or
    NaN, so those are written as the text ``settings_from_json`` reads back; booleans stay booleans."""
    return {k: v if isinstance(v, bool) or math.isfinite(v) else str(v) for k, v in settings.items()}


def settings_from_json(name: str, raw) -> tuple[dict[str, float | bool], list[str]]:
    """The settings of estimator ``name`` in ``raw`` (as ``settings_as_json`` wrote them, or by anybody) that
    this version has, each as its setting's type (a boolean or a number, inf and NaN included); and
    ``name.key`` for each left out: another version's setting, or a value not of its setting's type."""
    if not isinstance(raw, dict):
        return {}, [f"{name} (not a table of settings)"]
    cls = ESTIMATORS.get(name)
    defaults = dataclasses.asdict(cls.Settings()) if cls else {}
    kept, left_out = {}, []
    for key, value in raw.items():
        value = _NON_FINITE.get(value, value) if isinstance(value, str) else value
        default = defaults.get(key)
        if isinstance(default, bool):
            fits = isinstance(value, bool)
        else:
            # NaN only where the default is NaN ("from the data"), as ``create`` checks
            fits = (isinstance(default, float) and isinstance(value, (int, float)) and not isinstance(value, bool)
                    and (not math.isnan(value) or math.isnan(default)))
        if fits:
            kept[key] = value if isinstance(value, bool) else float(value)
        else:
            left_out.append(f"{name}.{key}")
    return kept, left_out


def create(name: str, overrides: dict[str, float] | None = None, compile: bool = True) -> Estimator:
    """An estimator by name with some settings replaced; ValueError names what is wrong. ``compile``
    False: never wait for numba, run the kernel interpreted if it is not in the cache
    (``Estimator.ready_or_interpreted``, a live session's)."""
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
    settings = dataclasses.replace(cls.Settings(), **(overrides or {}))
    return cls(settings) if compile else cls.ready_or_interpreted(settings)


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

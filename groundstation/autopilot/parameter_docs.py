"""What an autopilot's parameters mean, as Mission Planner and Flight Review show it: each parameter's
description, units, range, the meaning of its value (an enum's label, a bitmask's bits) and its default,
so that a non-default parameter stands out.

Where the words come from, first found wins (``docs_for``):

1. ``parameters.json`` beside the log: PX4's parameter metadata as its build writes it (and QGroundControl
   downloads it from the vehicle): ``{"parameters": [{"name", "shortDesc", "longDesc", "units", "min", "max",
   "default", "values": [{"value", "description"}], "bitmask": [{"index", "description"}]}]}``. PX4 publishes
   no package of it, so a flyer puts the one of their firmware there (``PX4_DOCS_HINT``).
2. ArduPilot's parameter documentation per vehicle (apm.pdef), as the ``mavio-params`` package ships it: the
   vehicle whose set names most of the log's parameters (a log seldom says its vehicle in one place; the
   names do: ``ATC_RAT_RLL_P`` is Copter's, ``Q_ENABLE`` Plane's). It is the latest firmware's: a parameter an
   older firmware meant otherwise reads as today's, as in Mission Planner.

Defaults: the log's own where it has them (``FlightLog.parameter_defaults``: DataFlash ``PARM.Default``,
ULog's parameter defaults), else the metadata's (PX4's ``default``; ArduPilot's documentation has none).
"""

from __future__ import annotations

import dataclasses
import json
import math
from importlib.metadata import version
from pathlib import Path

from mavio_params import definitions

from groundstation.errors import UserError

PX4_FILE = "parameters.json"
ARDUPILOT_VEHICLES = ("copter", "plane", "rover", "sub", "tracker", "blimp")
NAMED_AT_LEAST = 0.5  # of the log's parameters a vehicle's set names, to be taken as that vehicle's
PX4_DOCS_HINT = (f"No parameter descriptions: for a PX4 log, put the {PX4_FILE} of its firmware version (PX4's build "
                 f"makes it; QGroundControl reads the same) beside the log")


@dataclasses.dataclass(frozen=True)
class ParameterDoc:
    name: str
    title: str = ""  # a short name ("Gyro filter cutoff frequency")
    description: str = ""
    units: str = ""
    minimum: float | None = None
    maximum: float | None = None
    values: dict[float, str] = dataclasses.field(default_factory=dict)  # an enum's: value -> its meaning
    bits: dict[int, str] = dataclasses.field(default_factory=dict)  # a bitmask's: bit -> its meaning
    default: float | None = None

    def range_text(self) -> str:
        if self.minimum is None and self.maximum is None:
            return ""
        return f"{shown_value(self.minimum) if self.minimum is not None else ''} .. {shown_value(self.maximum) if self.maximum is not None else ''}"

    def meaning(self, value: float) -> str:
        """What ``value`` means: its enum label, or the labels of the bits it sets ("" when neither is known)."""
        if self.values:
            return self.values.get(float(value), "")
        if self.bits and float(value).is_integer() and value >= 0:
            return ", ".join(label for bit, label in sorted(self.bits.items()) if int(value) >> bit & 1)
        return ""


@dataclasses.dataclass(frozen=True)
class ParameterDocs:
    docs: dict[str, ParameterDoc]
    source: str  # where they come from, in words; or why there are none
    described: bool = False  # a source of descriptions was found (else ``docs`` holds the log's defaults alone)

    def get(self, name: str) -> ParameterDoc:
        return self.docs.get(name) or ParameterDoc(name)


def docs_for(parameters, beside: Path | None = None, defaults: dict[str, float] | None = None) -> ParameterDocs:
    """The docs of ``parameters`` (their names), the log's ``defaults`` over the metadata's; ``beside``: the
    log's folder, where a ``parameters.json`` is looked for. UserError when that file cannot be read."""
    names = set(parameters)
    found = _px4_file(beside / PX4_FILE) if beside is not None and (beside / PX4_FILE).is_file() else None
    if found is None and names:
        found = _ardupilot(names)
    docs, source = found or ({}, PX4_DOCS_HINT if names else "")
    for name, default in (defaults or {}).items():
        docs[name] = dataclasses.replace(docs.get(name) or ParameterDoc(name), default=default)
    return ParameterDocs(docs, source, found is not None)


def non_default(value: float, doc: ParameterDoc) -> bool:
    """A value that is not its default, to float32's precision (the precision parameters are sent and logged in)."""
    if doc.default is None or math.isnan(doc.default):
        return False
    return not math.isclose(value, doc.default, rel_tol=1e-6, abs_tol=1e-7)


def _ardupilot(names: set[str]) -> tuple[dict[str, ParameterDoc], str] | None:
    named = {vehicle: len(names & definitions(f"ardupilot.{vehicle}").keys()) for vehicle in ARDUPILOT_VEHICLES}
    vehicle = max(named, key=named.get)  # the first of equals
    if named[vehicle] < NAMED_AT_LEAST * len(names):
        return None
    docs = {name: _from_ardupilot(name, entry) for name, entry in definitions(f"ardupilot.{vehicle}").items() if name in names}
    return docs, (f"ArduPilot's parameter documentation for {vehicle.capitalize()} (its latest firmware; "
                  f"mavio-params {version('mavio-params')}): {named[vehicle]} of {len(names)} parameters described")


def _from_ardupilot(name: str, entry: dict) -> ParameterDoc:
    low, high = entry.get("range") or (None, None)
    return ParameterDoc(name, entry.get("display_name", ""), entry.get("description", ""), entry.get("units", ""),
                        _float(low), _float(high), {float(v): label for v, label in (entry.get("values") or {}).items()},
                        {int(bit): label for bit, label in (entry.get("bitmask") or {}).items()})


def _px4_file(path: Path) -> tuple[dict[str, ParameterDoc], str]:
    try:
        listed = json.loads(path.read_text(encoding="utf-8"))["parameters"]
        docs = {p["name"]: _from_px4(p) for p in listed}
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as error:
        raise UserError(f"{path}: not PX4's parameter metadata ({type(error).__name__}: {error})") from None
    return docs, f"{path} ({len(docs)} parameters described)"


def _from_px4(p: dict) -> ParameterDoc:
    short, long = p.get("shortDesc", ""), p.get("longDesc", "")
    return ParameterDoc(p["name"], short, f"{short}. {long}" if short and long else short or long, p.get("units", ""),
                        _float(p.get("min")), _float(p.get("max")),
                        {float(v["value"]): v["description"] for v in p.get("values", ())},
                        {int(b["index"]): b["description"] for b in p.get("bitmask", ())}, _float(p.get("default")))


def _float(value) -> float | None:
    return None if value is None or value == "" else float(value)


def shown_value(value: float) -> str:
    """Integers as integers (most parameters are), others to float32's precision, which they are sent in."""
    return f"{value:.0f}" if float(value).is_integer() else f"{value:.7g}"

"""What a session's tables hold: every column's name, unit, label and useful decimals.

Derived from the protocol spec, so adding a downlink frame to ``spec.toml`` gives the session a
table for it, and the exports, the workbook and the UI show it, with no Python typed for it: every
downlink frame becomes a table named after it (``MAG_RAW`` -> ``mag_raw``) whose columns are its
fields in physical units (raw * scale), named ``<field>_<unit>`` (``pressure_Pa``), after a
``time_s`` column of session time. The device timestamp itself is not a column: session time
replaces it (see docs/conventions.md).

A few tables are computed rather than decoded, and are described here too: ``imu`` (``IMU_RAW`` in
body axes and physical units, plus every estimator's quaternion and diagnostics), ``onboard``
(``ATTITUDE``: the aircraft's own estimate), ``position`` (seed 004's fused position), ``truth`` (a
simulator's attitude, in a flight log that has one) and the compass heading column of ``mag_raw``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re

from firmware_protocol.spec import SPEC, TIMESTAMP_FIELD, Field, FrameType, Spec
from groundstation.names import kept_apart

# A spec unit as a column-name suffix: dimensionless units add nothing, others say the unit.
_UNIT_SUFFIX = {"1": "", "enum": "", "bits": "", "index": "", "%": "_pct", "deg/s": "_deg_s", "m/s": "_m_s", "m/s2": "_m_s2"}
# Short forms of a unit that a spec field's name may end with already.
_UNIT_SHORT = {"deg/s": ("_dps",)}
# A spec unit as a person reads it in a header.
_UNIT_SHOWN = {"1": "", "enum": "enum", "bits": "bits", "index": "index", "uT": "µT", "degC": "°C", "deg": "°",
               "deg/s": "°/s", "us": "µs", "count": "count"}  # fmt: skip
# Tables whose export columns carry another prefix than the table's name (kept from earlier exports).
EXPORT_PREFIX = {"mag_raw": "mag", "position": "fused"}
# Frames whose tables belong to the link's health rather than to the sensors (the workbook's Link sheet).
LINK_TABLES = ("status", "radio_status", "sys_status")  # the last two: a MAVLink session's (session_makers/mavlink_front.py)
# How a session's product holds the host estimators' columns (every other column: float64): sized for showing, a
# float32 quaternion is within 6e-8 of its float64, far under a pixel; an hour of the app's ten estimators' 95
# columns at 100 Hz is 137 MB so, 274 MB in float64. An export computes its own in float64 (``held_dtype``).
ESTIMATES_HELD = "float32"
# Frames decoded into a computed table instead of a table of their own.
COMPUTED_FROM = {"IMU_RAW": "imu", "ATTITUDE": "onboard"}


@dataclasses.dataclass(frozen=True)
class Column:
    name: str  # in every export: snake_case with the unit as suffix
    unit: str  # the spec's unit ("1" for a plain number)
    label: str  # for a person, without the unit
    decimals: int | None = None  # digits worth showing (None: an integer count)
    description: str = ""
    held: str = "float64"  # the dtype a product holds it in (``session.product.held_dtype``): ``ESTIMATES_HELD``, a log's ``logtables.logged_dtype``

    @property
    def header(self) -> str:
        shown = "count" if self.unit == "1" and self.decimals is None else _UNIT_SHOWN.get(self.unit, self.unit)
        return f"{self.label} ({shown})" if shown else self.label


@dataclasses.dataclass(frozen=True)
class TableInfo:
    name: str
    label: str
    columns: tuple[Column, ...]  # time_s first
    frame: str | None = None  # the spec frame its rows come from
    timestamped: bool = True  # False: rows carry the time of the last timestamped frame (CONFIG, ACK)

    @functools.cached_property  # asked for every table of every product (a log has hundreds)
    def column_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.columns)

    @property
    def export_prefix(self) -> str:
        return EXPORT_PREFIX.get(self.name, self.name)

    def column(self, name: str) -> Column:
        for column in self.columns:
            if column.name == name:
                return column
        raise KeyError(f"table {self.name} has no column {name!r}")


TIME = Column("time_s", "s", "time", 3, "session time: seconds from the first sample, monotonic across device resets")


def column_name(field: Field) -> str:
    """``<field>_<unit>``; a field whose name ends with its unit already (``rate_hz``, or the short form
    ``gyro_fs_dps``) keeps its name: one unit suffix, not ``rate_hz_Hz``."""
    suffix = _UNIT_SUFFIX.get(field.unit, "_" + field.unit.replace("/", "_"))
    if field.name.lower().endswith((suffix.lower(), *_UNIT_SHORT.get(field.unit, ()))):
        return field.name
    return field.name + suffix


def decimals_for(scale: float, c_type: str) -> int | None:
    """Digits that a value with this resolution needs; None for whole counts."""
    if c_type in ("float", "double"):
        return 4
    if scale == 1.0:
        return None
    return max(0, math.ceil(-math.log10(scale) - 1e-9))


def field_column(field: Field) -> Column:
    return Column(column_name(field), field.unit, field.name.replace("_", " "), decimals_for(field.scale, field.c_type),
                  field.description)


def frame_table(frame_type: FrameType) -> TableInfo:
    """The table every downlink frame gets: its fields in physical units after session time."""
    fields = [f for f in frame_type.fields if f.name != TIMESTAMP_FIELD]
    return TableInfo(frame_type.name.lower(), frame_type.description, (TIME, *map(field_column, fields)),
                     frame_type.name, frame_type.has_timestamp)


_UNIT_SLUG = re.compile(r"[^A-Za-z0-9]+")  # "m/s" -> "m_s", "cdeg" stays


def message_table(name: str, label: str, fields, units: dict[str, str], renamed: list[str] | None = None,
                  held: dict[str, str] | None = None) -> TableInfo:
    """The table of a message of another protocol (an autopilot's MAVLink message, live or logged):
    ``time_s``, then one column per field named ``<field>_<unit>`` with the unit its definition gives
    (``m/s`` -> ``_m_s``, ``%`` -> ``_pct``; none -> the bare field name). Two fields that would share a
    name (``Alt`` in m and ``Alt_m``) are kept apart (``names.kept_apart``); ``renamed`` is told the warnings.
    ``held``: field -> the dtype the product holds it in (``Column.held``; float64 for a field not named)."""
    held = held or {}
    columns = [_message_column(field, units.get(field) or "", held.get(field, "float64")) for field in fields]
    names, warnings = kept_apart([c.name for c in columns], [f"{name}.{field}" for field in fields], "column")
    if renamed is not None:
        renamed += warnings
    columns = [c if c.name == n else dataclasses.replace(c, name=n) for c, n in zip(columns, names)]
    return TableInfo(name.lower(), label, (TIME, *columns))


@functools.cache  # the same fields in every instance of a topic or message type, in every log
def _message_column(field: str, unit: str, held: str) -> Column:
    slug = _UNIT_SLUG.sub("_", unit.replace("%", "pct").replace("µ", "u").replace("μ", "u")).strip("_")
    return Column(f"{field}_{slug}" if slug else field, unit or "1", field, 3, held=held)


def _columns(*specs: tuple) -> tuple[Column, ...]:
    return tuple(Column(*spec) for spec in specs)


IMU = TableInfo("imu", "IMU samples in body axes (FRD) and physical units", (TIME, *_columns(
    ("device_time_us", "us", "device time", None, "the aircraft's clock, unwrapped; restarts at a device reset"),
    ("host_time_s", "s", "host arrival time", 3, "when the chunk holding the sample arrived, from the first chunk"),
    ("acc_x_g", "g", "acc x", 4, "specific force, body x (forward)"),
    ("acc_y_g", "g", "acc y", 4, "specific force, body y (right)"),
    ("acc_z_g", "g", "acc z", 4, "specific force, body z (down)"),
    ("gyr_x_rad_s", "rad/s", "gyro x", 5, "angular rate about body x"),
    ("gyr_y_rad_s", "rad/s", "gyro y", 5, "angular rate about body y"),
    ("gyr_z_rad_s", "rad/s", "gyro z", 5, "angular rate about body z"),
    ("temperature_c", "degC", "IMU temperature", 2, "die temperature"),
)), "IMU_RAW")  # fmt: skip
ONBOARD = TableInfo("onboard", "the aircraft's own attitude estimate (ATTITUDE)", (TIME, *_columns(
    ("device_time_us", "us", "device time", None, "the aircraft's clock, unwrapped"),
    ("qw", "1", "onboard qw", 5), ("qx", "1", "onboard qx", 5), ("qy", "1", "onboard qy", 5), ("qz", "1", "onboard qz", 5),
    ("lambda", "1", "onboard λ", 3, "the onboard AHF's gain (seed 000 eq. 20)"),
    ("flags", "bits", "onboard flags", None),
)), "ATTITUDE")  # fmt: skip
POSITION = TableInfo("position", "fused position (seed 004), NED metres from the first GPS fix", (TIME, *_columns(
    ("pos_n_m", "m", "fused north", 3), ("pos_e_m", "m", "fused east", 3), ("pos_d_m", "m", "fused down", 3),
    ("vel_n_m_s", "m/s", "fused velocity N", 2), ("vel_e_m_s", "m/s", "fused velocity E", 2),
    ("vel_d_m_s", "m/s", "fused velocity D", 2),
)))  # fmt: skip
TRUTH = TableInfo("truth", "the true attitude (a simulator's), body -> NED", (TIME, *_columns(
    ("qw", "1", "true qw", 5), ("qx", "1", "true qx", 5), ("qy", "1", "true qy", 5), ("qz", "1", "true qz", 5),
)))  # fmt: skip
HEADING = Column("heading_deg", "deg", "compass heading", 2, "tilt-compensated, from the aiding estimator's pitch and roll")


# A diagnostic's unit read from its name's suffix (the project's naming rule, longest suffix first), and
# the diagnostics whose names carry none: AHF's λ is a rate (seed 000, eq. 20).
_SUFFIX_UNIT = (("_rad_s", "rad/s"), ("_deg_s", "deg/s"), ("_m_s2", "m/s2"), ("_m_s", "m/s"), ("_pct", "%"),
                ("_deg", "deg"), ("_rad", "rad"), ("_uT", "uT"), ("_s", "s"), ("_m", "m"))
_DIAGNOSTIC_NAMED = {"lam": ("λ", "rad/s"), "e_a": ("e_a", "1"), "status": ("status", "bits")}


def diagnostic_column(name: str, diagnostic: str) -> Column:
    """An estimator's diagnostic as a channel: "ahf2 bias x" in rad/s for ``ahf2_bias_x_rad_s``."""
    if diagnostic in _DIAGNOSTIC_NAMED:
        text, unit = _DIAGNOSTIC_NAMED[diagnostic]
    else:
        suffix, unit = next(((s, u) for s, u in _SUFFIX_UNIT if diagnostic.endswith(s)), ("", "1"))
        text = diagnostic.removesuffix(suffix).replace("_", " ")
    return Column(f"{name}_{diagnostic}", unit, f"{name} {text}", 4, held=ESTIMATES_HELD)


def estimator_columns(name: str, diagnostics: tuple[str, ...]) -> tuple[Column, ...]:
    """An estimator's columns in the ``imu`` table: its quaternion (body -> NED) and diagnostics."""
    quaternion = tuple(Column(f"{name}_q{c}", "1", f"{name} q{c}", 6, held=ESTIMATES_HELD) for c in "wxyz")
    return quaternion + tuple(diagnostic_column(name, d) for d in diagnostics)


@dataclasses.dataclass(frozen=True)
class Catalogue:
    """Every table of a session, in a stable order: computed tables first, then one per frame."""

    tables: dict[str, TableInfo]

    def __getitem__(self, name: str) -> TableInfo:
        return self.tables[name]

    def __iter__(self):
        return iter(self.tables.values())

    def __contains__(self, name: str) -> bool:
        return name in self.tables

    def frame_tables(self) -> list[TableInfo]:
        """The tables decoded straight from a frame (what ``COMPUTED_FROM`` does not claim)."""
        return [t for t in self if t.frame is not None and t.frame not in COMPUTED_FROM]

    def channels(self) -> list[tuple[TableInfo, Column]]:
        """Every plottable column of every table (time excluded)."""
        return [(t, c) for t in self for c in t.columns if c.name != TIME.name]


def session_catalogue(estimators: dict[str, tuple[str, ...]], spec: Spec = SPEC) -> Catalogue:
    """The catalogue of a session running ``estimators`` (name -> diagnostic fields) on ``spec``."""
    imu = dataclasses.replace(IMU, columns=IMU.columns + sum((estimator_columns(n, d) for n, d in estimators.items()), ()))
    tables = {"imu": imu, "onboard": ONBOARD}
    for frame_type in spec.frames:
        if frame_type.direction == "down" and frame_type.name not in COMPUTED_FROM:
            tables[frame_type.name.lower()] = frame_table(frame_type)
    if "mag_raw" in tables:
        tables["mag_raw"] = dataclasses.replace(tables["mag_raw"], columns=tables["mag_raw"].columns + (HEADING,))
    tables["position"] = POSITION
    return Catalogue(tables)

"""A flyer's sections of a flight log, as Mission Planner's graphs and PX4 Flight Review show them: the
attitude the controller asked for against the one it had, the same for the body rates, the battery, the GPS
quality and the actuator outputs. Each is a table of the session (``SECTIONS``), in the catalogue with its
units in its column names, made from the tables the log's readers already make (``logtables``, the MAVLink
front-end's generic tables), so the plots, the Channels tab, the exports and the report read them as any
other table. A section a log does not hold is not made.

Where each comes from, first found wins (``Source``):

| table | ArduPilot DataFlash | PX4 ULog | MAVLink (.tlog) |
|---|---|---|---|
| ``attitude_setpoint`` | ``ATT`` DesRoll, DesPitch, DesYaw | ``vehicle_attitude_setpoint`` roll/pitch/yaw_body (rad), else ``q_d`` | ``ATTITUDE_TARGET`` q, else ``NAV_CONTROLLER_OUTPUT`` nav_roll, nav_pitch |
| ``attitude`` | ``ATT`` Roll, Pitch, Yaw | the onboard estimate (``vehicle_attitude``) | the onboard estimate (``ATTITUDE``) |
| ``rates_setpoint`` | ``RATE`` RDes, PDes, YDes | ``vehicle_rates_setpoint`` roll, pitch, yaw (rad/s) | ``ATTITUDE_TARGET`` body rates |
| ``rates`` | ``RATE`` R, P, Y | ``vehicle_angular_velocity`` xyz (rad/s), else ``vehicle_attitude`` roll/pitch/yawspeed | the IMU's gyro |
| ``battery`` | ``BAT`` Volt, Curr, RemPct, CurrTot | ``battery_status`` voltage_v, current_a, remaining (0..1), discharged_mah | ``SYS_STATUS``; ``BATTERY_STATUS`` current_consumed |
| ``gps_quality`` | ``GPS`` Status, NSats, HDop | ``vehicle_gps_position`` fix_type, satellites_used, hdop | ``GPS_RAW_INT`` fix_type, satellites_visible, eph (HDOP × 100) |
| ``outputs`` | ``RCOU`` C1..C14 (µs) | ``actuator_outputs`` output_0.. (its values: PWM µs on PX4 1.12) | ``SERVO_OUTPUT_RAW`` servo1..16_raw (µs) |

A source column's unit is the catalogue's (DataFlash's FMTU, pymavlink's units), else the one ``Source``
gives (ULog carries none); ``converted`` is the one rule from it to the section's unit. Angles of a
quaternion are ZYX Euler angles (``quaternion.to_euler_zyx``; w first). Every row of a source table is kept,
on its own time: no resampling.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from groundstation import quaternion
from groundstation.palette import ACTUAL_COLOUR, DESIRED_COLOUR, PALETTE
from groundstation.session_parts.catalogue import TIME, Catalogue, Column, TableInfo

AXES = ("roll", "pitch", "yaw")
# (from, to) -> factor: the one place a source's unit becomes a section's
FACTORS = {("deg", "deg"): 1.0, ("degheading", "deg"): 1.0, ("cdeg", "deg"): 0.01, ("rad", "deg"): 180.0 / math.pi,
           ("deg/s", "deg/s"): 1.0, ("rad/s", "deg/s"): 180.0 / math.pi, ("V", "V"): 1.0, ("mV", "V"): 1e-3,
           ("A", "A"): 1.0, ("cA", "A"): 0.01, ("%", "%"): 1.0, ("fraction", "%"): 100.0, ("mAh", "mAh"): 1.0,
           ("Ah", "mAh"): 1000.0, ("1", "1"): 1.0, ("centi", "1"): 0.01, ("us", "us"): 1.0, ("enum", "enum"): 1.0}
MAX_OUTPUTS = 16  # output channels a section shows (SERVO_OUTPUT_RAW's 16, RCOU's 14, actuator_outputs' 16)


def converted(values: np.ndarray, unit: str, to: str) -> np.ndarray:
    """``values`` in ``unit`` as ``to``; ValueError for a pair without a rule (a source described wrongly)."""
    try:
        return np.asarray(values, dtype=float) * FACTORS[(unit, to)]
    except KeyError:
        raise ValueError(f"no conversion from {unit!r} to {to!r}") from None


@dataclasses.dataclass(frozen=True)
class Source:
    """One table a section can be made from: ``columns`` maps the section's column to the source's, whose
    unit is the catalogue's unless ``units`` names it; ``quaternion``: four source columns (w first) whose
    ZYX angles give ``roll``, ``pitch``, ``yaw`` (the section's ``<axis>_deg``)."""

    table: str
    columns: dict[str, str] = dataclasses.field(default_factory=dict)
    units: dict[str, str] = dataclasses.field(default_factory=dict)
    quaternion: tuple[str, str, str, str] | None = None
    unknown: dict[str, float] = dataclasses.field(default_factory=dict)  # a source column's "not measured" value: NaN

    def present(self, tables: dict) -> bool:
        """The table has rows, its quaternion's four columns if it gives one, and at least one other column."""
        table = tables.get(self.table)
        if table is None or not len(table.get("time_s", ())):
            return False
        if self.quaternion is not None:
            return all(c in table for c in self.quaternion)
        return any(c in table for c in self.columns.values())


def _axes(fmt: str, unit: str, **kw) -> tuple[Column, ...]:
    return tuple(Column(fmt.format(axis=a), unit, kw.get("label", "{axis}").format(axis=a), 2) for a in AXES)


@dataclasses.dataclass(frozen=True)
class Section:
    info: TableInfo
    sources: tuple[Source, ...]


def _ardupilot_axes(table: str, fields: tuple[str, str, str], unit_suffix: str) -> Source:
    return Source(table, {f"{a}_{unit_suffix}": f for a, f in zip(AXES, fields)})


DEG, DEG_S = "deg", "deg_s"
ATTITUDE_SETPOINT = TableInfo("attitude_setpoint", "the attitude the autopilot's controller asked for (ZYX, body -> NED)",
                              (TIME, *_axes("{axis}_deg", "deg", label="desired {axis}")))
ATTITUDE = TableInfo("attitude", "the attitude the autopilot's controller had (its own estimate; ZYX, body -> NED)",
                     (TIME, *_axes("{axis}_deg", "deg", label="{axis}")))
RATES_SETPOINT = TableInfo("rates_setpoint", "the body rates the autopilot's rate controller asked for",
                           (TIME, *_axes("{axis}_deg_s", "deg/s", label="desired {axis} rate")))
RATES = TableInfo("rates", "the body rates the autopilot's rate controller had", (TIME, *_axes("{axis}_deg_s", "deg/s", label="{axis} rate")))
BATTERY = TableInfo("battery", "the battery as the autopilot measures it", (TIME,
    Column("voltage_V", "V", "battery voltage", 2), Column("current_A", "A", "battery current", 2),
    Column("remaining_pct", "%", "battery remaining", 0), Column("used_mAh", "mAh", "charge used", 0)))  # fmt: skip
GPS_QUALITY = TableInfo("gps_quality", "the GPS receiver's fix", (TIME,
    Column("fix_type", "enum", "GPS fix type"), Column("satellites", "1", "satellites"), Column("hdop", "1", "HDOP", 2)))  # fmt: skip
OUTPUTS = TableInfo("outputs", "the autopilot's actuator outputs (PWM)",
                    (TIME, *(Column(f"out_{i}_us", "us", f"output {i}", 0) for i in range(1, MAX_OUTPUTS + 1))))

SECTIONS = (
    Section(ATTITUDE_SETPOINT, (
        _ardupilot_axes("att", ("DesRoll_deg", "DesPitch_deg", "DesYaw_degheading"), DEG),
        Source("vehicle_attitude_setpoint", {f"{a}_deg": f"{a}_body" for a in AXES}, dict.fromkeys((f"{a}_body" for a in AXES), "rad")),
        Source("vehicle_attitude_setpoint", quaternion=("q_d_0", "q_d_1", "q_d_2", "q_d_3")),
        Source("attitude_target", quaternion=("q_0", "q_1", "q_2", "q_3")),
        Source("nav_controller_output", {"roll_deg": "nav_roll_deg", "pitch_deg": "nav_pitch_deg"}),
    )),
    Section(ATTITUDE, (
        _ardupilot_axes("att", ("Roll_deg", "Pitch_deg", "Yaw_degheading"), DEG),
        Source("vehicle_attitude", quaternion=("q_0", "q_1", "q_2", "q_3")),  # on its own rows (the onboard table: on the IMU's)
        Source("onboard", quaternion=("qw", "qx", "qy", "qz")),
    )),
    Section(RATES_SETPOINT, (
        _ardupilot_axes("rate", ("RDes_deg_s", "PDes_deg_s", "YDes_deg_s"), DEG_S),
        Source("vehicle_rates_setpoint", {f"{a}_deg_s": a for a in AXES}, dict.fromkeys(AXES, "rad/s")),
        Source("attitude_target", {f"{a}_deg_s": f"body_{a}_rate_rad_s" for a in AXES}),
    )),
    Section(RATES, (
        _ardupilot_axes("rate", ("R_deg_s", "P_deg_s", "Y_deg_s"), DEG_S),
        Source("vehicle_angular_velocity", {f"{a}_deg_s": f"xyz_{i}" for i, a in enumerate(AXES)},
               dict.fromkeys((f"xyz_{i}" for i in range(3)), "rad/s")),
        Source("vehicle_attitude", {f"{a}_deg_s": f"{a}speed" for a in AXES}, dict.fromkeys((f"{a}speed" for a in AXES), "rad/s")),
        Source("imu", {f"{a}_deg_s": f"gyr_{x}_rad_s" for a, x in zip(AXES, "xyz")}),
    )),
    Section(BATTERY, tuple(
        Source(name, {"voltage_V": "Volt_V", "current_A": "Curr_A", "remaining_pct": "RemPct_pct", "used_mAh": "CurrTot_mAh"})
        for name in ("bat_0", "bat")) + (
        Source("battery_status", {"voltage_V": "voltage_v", "current_A": "current_a", "remaining_pct": "remaining",
                                  "used_mAh": "discharged_mah"},
               {"voltage_v": "V", "current_a": "A", "remaining": "fraction", "discharged_mah": "mAh"},
               unknown={"current_a": -1.0, "remaining": -1.0}),  # PX4: -1 if unknown
        Source("sys_status", {"voltage_V": "voltage_V", "current_A": "current_A", "remaining_pct": "remaining_pct"}),
    )),
    Section(GPS_QUALITY, tuple(
        Source(name, {"fix_type": "Status", "satellites": "NSats_satellites", "hdop": "HDop_m"},
               {"Status": "enum", "NSats_satellites": "1", "HDop_m": "1"})  # FMTU calls HDOP metres: it has no unit
        for name in ("gps_0", "gps_log")) + (
        Source("vehicle_gps_position", {"fix_type": "fix_type", "satellites": "satellites_used", "hdop": "hdop"},
               {"fix_type": "enum", "satellites_used": "1", "hdop": "1"}),
        Source("gps_raw_int", {"fix_type": "fix_type", "satellites": "satellites_visible", "hdop": "eph"},
               {"fix_type": "enum", "satellites_visible": "1", "eph": "centi"},  # eph: HDOP in hundredths
               unknown={"satellites_visible": 255.0, "eph": 65535.0}),  # MAVLink's "unknown": UINT8_MAX, UINT16_MAX
    )),
    Section(OUTPUTS, (
        Source("rcou", {f"out_{i}_us": f"C{i}_us" for i in range(1, 15)}),
        Source("actuator_outputs", {f"out_{i + 1}_us": f"output_{i}" for i in range(MAX_OUTPUTS)},
               dict.fromkeys((f"output_{i}" for i in range(MAX_OUTPUTS)), "us")),
        Source("servo_output_raw", {f"out_{i}_us": f"servo{i}_raw_us" for i in range(1, MAX_OUTPUTS + 1)}),
    )),
)

NAMES = tuple(section.info.name for section in SECTIONS)


def section_tables(tables: dict[str, dict[str, np.ndarray]], catalogue: Catalogue) -> dict[str, tuple[TableInfo, dict]]:
    """Each section the session's ``tables`` hold: its ``TableInfo`` (the columns it has) and its columns, by name."""
    made = {}
    for section in SECTIONS:
        source = next((s for s in section.sources if s.present(tables)), None)
        if source is not None:
            columns = _made(section.info, source, tables[source.table], catalogue)
            info = dataclasses.replace(section.info, columns=tuple(c for c in section.info.columns if c.name in columns))
            made[section.info.name] = (info, columns)
    return made


def _made(info: TableInfo, source: Source, table: dict[str, np.ndarray], catalogue: Catalogue) -> dict[str, np.ndarray]:
    units = {c.name: c.unit for c in catalogue[source.table].columns} if source.table in catalogue else {}
    wanted = {c.name: c.unit for c in info.columns}
    columns = {"time_s": np.asarray(table["time_s"], dtype=float)}
    if source.quaternion is not None:
        q = np.column_stack([np.asarray(table[c], dtype=float) for c in source.quaternion])
        yaw, pitch, roll = np.moveaxis(np.degrees(quaternion.to_euler_zyx(q)), -1, 0)
        columns.update(roll_deg=roll, pitch_deg=pitch, yaw_deg=yaw)
    for name, column in source.columns.items():
        if column in table:  # a log's older or smaller form lacks some (BAT before RemPct, RCOU's 14 of 16)
            values = np.asarray(table[column], dtype=float)
            if column in source.unknown:
                values = np.where(values == source.unknown[column], np.nan, values)
            columns[name] = converted(values, source.units.get(column) or units.get(column, "1"), wanted[name])
    return {name: columns[name] for name in wanted if name in columns}  # in the catalogue's order


def attach_sections(data) -> None:
    """The sections an autopilot's session ``data`` (a ``SessionData`` of protocol "mavlink": a flight log, a
    recorded MAVLink link) holds, added to its tables and catalogue after its own. The project's own aircraft has
    no controller to show: its sessions get none."""
    if data.protocol != "mavlink":
        return
    made = {name: made for name, made in section_tables(data.tables, data.catalogue).items()
            if name not in data.tables}  # a log's own table of that name (none known today) stays as it is
    if made:
        data.catalogue = Catalogue({**data.catalogue.tables, **{name: info for name, (info, _) in made.items()}})
        data.tables.update({name: columns for name, (_, columns) in made.items()})


# -- how the sections are shown: the app's Flight tab and the report draw the same pages ---------------------


@dataclasses.dataclass(frozen=True)
class Trace:
    table: str
    column: str
    label: str
    colour: str


@dataclasses.dataclass(frozen=True)
class Figure:
    title: str
    unit: str  # as shown ("°/s"); "" for a count or a code
    traces: tuple[Trace, ...]
    wraps_at: float | None = None  # the period of a circular quantity: no line across its wrap (a heading's 360°)


@dataclasses.dataclass(frozen=True)
class Page:
    title: str
    figures: tuple[Figure, ...]

    @property
    def tables(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(t.table for f in self.figures for t in f.traces))


def _versus(setpoint: str, actual: str, suffix: str, unit: str, title: str) -> tuple[Figure, ...]:
    """One figure per axis: what the controller asked for and what it had."""
    return tuple(Figure(title.format(axis=axis), unit, (Trace(setpoint, f"{axis}_{suffix}", "desired", DESIRED_COLOUR),
                                                        Trace(actual, f"{axis}_{suffix}", "actual", ACTUAL_COLOUR)),
                        360.0 if axis == "yaw" and suffix == "deg" else None)  # yaw: 0..360 or ±180
                 for axis in AXES)


def _each(table: str, columns: tuple[tuple[str, str, str], ...]) -> tuple[Figure, ...]:
    return tuple(Figure(title, unit, (Trace(table, column, title, ACTUAL_COLOUR),)) for column, title, unit in columns)


OUTPUT_COLOURS = tuple(PALETTE.values())
PAGES = (
    Page("Attitude", _versus(ATTITUDE_SETPOINT.name, ATTITUDE.name, "deg", "°", "{axis}")),
    Page("Rates", _versus(RATES_SETPOINT.name, RATES.name, "deg_s", "°/s", "{axis} rate")),
    Page("Battery", _each(BATTERY.name, (("voltage_V", "voltage", "V"), ("current_A", "current", "A"),
                                         ("remaining_pct", "remaining", "%")))),
    Page("GPS", _each(GPS_QUALITY.name, (("fix_type", "fix type", ""), ("satellites", "satellites", ""), ("hdop", "HDOP", "")))),
    Page("Outputs", (Figure("outputs", "µs", tuple(Trace(OUTPUTS.name, f"out_{i}_us", str(i), OUTPUT_COLOURS[(i - 1) % len(OUTPUT_COLOURS)])
                                                   for i in range(1, MAX_OUTPUTS + 1))),)),
)


def pages_of(catalogue: Catalogue) -> list[Page]:
    """The pages the session has, each with the traces whose columns it has (a tlog's desired attitude has no yaw,
    RCOU 14 outputs of 16); a figure left with none is left out, and a page left with none."""
    has = {(t.name, c.name) for t in catalogue if t.name in NAMES for c in t.columns}
    pages = []
    for page in PAGES:
        figures = tuple(dataclasses.replace(f, traces=kept) for f in page.figures
                        if (kept := tuple(t for t in f.traces if (t.table, t.column) in has)))
        if figures:
            pages.append(dataclasses.replace(page, figures=figures))
    return pages

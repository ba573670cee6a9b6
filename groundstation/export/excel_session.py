"""The workbook's ``Session`` sheet: what was flown, with what, how the link did, and how well the
estimators did when the session has truth. A short sheet of labelled rows with a few small tables.
"""

from __future__ import annotations

import math
from datetime import datetime

import numpy as np
from openpyxl.cell import WriteOnlyCell
from openpyxl.styles import Font

from firmware_protocol import SPEC
from groundstation import mounting
from groundstation.errors import UserError
from groundstation.export.excel_columns import DATE_TIME, start_time
from groundstation.export.excel_stream import text_cell
from groundstation.session_parts.figures import rate_hz
from groundstation.session.product import SessionData

WIDTHS = {"A": 38, "B": 24, "C": 24, "D": 70, "E": 24}
LINK_COUNTS = (
    ("frames", "frames received (count)"), ("frames_lost", "frames lost (count)"),
    ("crc_errors", "CRC failures (count)"), ("bytes_in", "bytes received (B)"),
    ("bytes_skipped", "bytes skipped (B)"), ("duplicates", "duplicate frames (count)"),
)  # fmt: skip
GYRO_CALIBRATION = SPEC.frame("CONFIG").field("gyro_calibration")  # "unknown" from firmware older than the field
SHOWN_METADATA = {"source", "port", "start_utc", "app_version", "protocol_version", "estimator_settings", "filters",
                  "imu_rate_hz"}  # the IMU rate: computed for every session (``SessionData.imu_rate_hz``)
# The other header fields, by what a reader calls them (a field not listed: its name with spaces).
METADATA_LABELS = {
    "source_spec": "source (as typed)", "format": "file format", "format_version": "recording format version",
    "protocol": "link protocol", "protocol_fingerprint": "protocol fingerprint (ground station)",
    "vehicle_system": "MAVLink vehicle (system id)", "aiding_estimator": "aiding estimator",
    "autopilot": "autopilot", "imu_choice": "IMU for the estimators", "imu_warning": "IMU warning",
    "time_origin_s": "time origin (s)", "notes": "notes",
}  # fmt: skip
PROTOCOLS = {"gs": "the project's own (firmware_protocol)", "mavlink": "MAVLink (an autopilot)"}


class Heading(str):
    """A section title or a table's column header: written bold."""


def session_rows(data: SessionData, rows: np.ndarray, forced: dict | None = None) -> list[list]:
    """The sheet as rows of values; ``forced``: the caller's setting overrides (``--set``)."""
    out = [[Heading("Session")], *facts(data, rows), []]
    if data.link is not None:
        out += [[Heading("Link")], *([label, data.link.counters[name]] for name, label in LINK_COUNTS),
                ["frames lost (%)", loss if math.isfinite(loss := data.link_loss_pct()) else None], []]
    if data.estimated:
        out += settings_table(data, forced or {})
    out += events_table(data)
    if data.true_q is not None:
        out += error_table(data)
    elif data.has_onboard() and data.estimated:
        out += agreement_table(data)
    return out


def facts(data: SessionData, rows: np.ndarray) -> list[list]:
    meta, time_s = data.metadata, data.time_s
    out = [[key, meta[key]] for key in ("source", "port") if key in meta]
    start = start_time(meta)
    if start is not None:
        out.append(["recording started (UTC)", start])
    out += [
        ["duration (s)", data.duration_s()],
        ["samples (count)", len(data)],
        ["exported rows (count)", len(rows)],
        ["exported from (s)", float(time_s[rows[0]])],
        ["exported to (s)", float(time_s[rows[-1]])],
    ]
    if len(rows) > 1:
        out.append(["exported rate (Hz)", rate_hz(time_s[rows])])
    if math.isfinite(imu_hz := data.imu_rate_hz()):
        out.append(["IMU rate (Hz)", imu_hz])
    out += [[label, meta[key]] for key, label in (("app_version", "ground station version"),
                                                  ("protocol_version", "protocol version (ground station)")) if key in meta]
    out += firmware(data)
    out += [[METADATA_LABELS.get(key, key.replace("_", " ")), PROTOCOLS.get(value, value) if key == "protocol" else value]
            for key, value in meta.items()
            if key not in SHOWN_METADATA and isinstance(value, (str, int, float)) and not isinstance(value, bool)]
    return out


def firmware(data: SessionData) -> list[list]:
    """What the aircraft's last CONFIG frame said; a dataset has no aircraft."""
    if "autopilot" in data.metadata or data.protocol == "mavlink":  # an autopilot sends no CONFIG frame
        return [["mounting", "the autopilot's body axes (x forward, y right, z down), as it sends them"]]
    if data.link is None:
        return [["mounting", "dataset: the IMU axes are taken as the body axes"]]
    config = data.config
    if config is None:
        return [["firmware", "no CONFIG frame received"]]
    return [
        ["firmware version", f"{config['fw_major']}.{config['fw_minor']}.{config['fw_patch']}"],
        ["protocol version (firmware)", config["protocol_version"]],
        ["accelerometer full scale (±g)", config["accel_fs_g"]],
        ["gyroscope full scale (±°/s)", config["gyro_fs_dps"]],
        ["output rate (Hz)", config["rate_hz"]],
        ["mounting (index)", config["mounting"]],
        ["mounting", mounting.describe(config["mounting"]) if 0 <= config["mounting"] < 24 else "invalid index"],
        ["gyro calibration", SPEC.enum_name(GYRO_CALIBRATION, config["gyro_calibration"])],
    ]


def settings_table(data: SessionData, forced: dict) -> list[list]:
    """Every estimator's settings at the start (recorded, then forced) and at the end (changed during the session)."""
    out = [[Heading("Estimator settings"), Heading("at start"), Heading("at end")]]
    for name in data.estimated:
        start, end = data.settings_at_start[name], data.settings_at_end[name]
        out += [[f"{name}.{param}", cell_number(value), cell_number(end[param])] for param, value in start.items()]
    if forced:
        out.append([f"forced for this export (--set): {forced}"])
    return out + [[]]


def events_table(data: SessionData) -> list[list]:
    """Settings changes, CONFIG frames and warnings in stream order, then what the recording lost."""
    if not data.events and not data.damage:
        return []
    out = [[Heading("Events"), Heading("time (s from first byte)"), Heading("kind"), Heading("what")]]
    out += [["", event["t_s"], event["kind"], describe_event(event)] for event in data.events]
    out += [["", None, "damage", finding] for finding in data.damage]
    return out + [[]]


def describe_event(event: dict) -> str:
    if event["kind"] == "settings":
        return ", ".join(f"{event['name']}.{k} = {v if isinstance(v, (bool, str)) else format(v, 'g')}"
                         for k, v in event["settings"].items())
    if event["kind"] == "config":
        return (f"CONFIG: firmware {event['fw_major']}.{event['fw_minor']}.{event['fw_patch']}, ±{event['accel_fs_g']} g, "
                f"±{event['gyro_fs_dps']} °/s, {event['rate_hz']} Hz, mounting {event['mounting']}, "
                f"gyro calibration {SPEC.enum_name(GYRO_CALIBRATION, event['gyro_calibration'])}")
    if "message" in event:
        return str(event["message"])
    return ", ".join(f"{k} = {v}" for k, v in event.items() if k not in ("t_host_ns", "t_s", "session_time_s", "kind"))  # e.g. an ACK


def error_table(data: SessionData) -> list[list]:
    """BROAD's inclination error of each estimator against the truth, over the whole session."""
    title = "Error against truth (whole session" + (", moving samples)" if data.moving is not None else ")")
    try:
        scores = data.evaluate()
    except UserError as error:
        return [[Heading(title)], [str(error)], []]
    out = [[Heading(title), Heading("inclination RMSE (°)"), Heading("inclination max (°)")]]
    return out + [[name, s["incl_rmse_deg"], s["incl_max_deg"]] for name, s in scores.items()] + [[]]


def agreement_table(data: SessionData) -> list[list]:
    """Without truth: each estimator's pitch/roll difference from the aircraft's own estimate."""
    from groundstation.autopilot.agreement import onboard_agreement

    out = [[Heading("Agreement with the onboard estimate (whole session; a difference, not an error: the onboard estimate is not truth)")],
           [Heading("estimator"), Heading("pitch RMS difference (°)"), Heading("pitch max difference (°)"),
            Heading("roll RMS difference (°)"), Heading("roll max difference (°)")]]  # fmt: skip
    for name, f in onboard_agreement(data).items():
        out.append([name, f["pitch_rms_deg"], f["pitch_max_deg"], f["roll_rms_deg"], f["roll_max_deg"]])
    return out + [[]]


def cell_number(value: float):
    """Excel has no infinity or NaN: those are written as text."""
    return value if math.isfinite(value) else str(value)


def write_session_sheet(workbook, rows: list[list]) -> None:
    sheet = workbook.create_sheet("Session")
    for letter, width in WIDTHS.items():
        sheet.column_dimensions[letter].width = width
    bold = Font(bold=True)
    for row in rows:
        cells = []
        for value in row:
            cell = text_cell(sheet, value) if isinstance(value, str) else WriteOnlyCell(sheet, value=value)
            if isinstance(value, Heading):
                cell.font = bold
            elif isinstance(value, datetime):
                cell.number_format = DATE_TIME
            elif isinstance(value, float):
                cell.number_format = "0.000"
            cells.append(cell)
        sheet.append(cells)

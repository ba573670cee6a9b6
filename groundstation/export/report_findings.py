"""What a flight report points out first: findings read off a session's product, ranked by severity.

Each rule reads what the product already holds (its events, tables, link figures), the vibration
summary (``analysis.vibration``) and the estimators' agreement (``autopilot.agreement``); none
recomputes them. Thresholds are named here with where they come from.

Incidents (``incidents``): what the autopilot logged about the flight going wrong, each a finding with its
time (the first evidence), severity and evidence: its texts, ``ERR`` and ``EV`` (``INCIDENT_TEXTS``), the
attitude far from its demand as ArduCopter's crash check judges it (``ATT``), the board's supply
(``POWR``, MAVLink ``POWER_STATUS``), the accelerometer's clip counters (``VIBE``), the EKF's normalised innovations (``XKF4``/``NKF4``)
and the magnetic field's strength (the compass, ``mag_raw``). Evidence of one kind within ``INCIDENT_JOIN_S`` of the
last is one incident. A crash is ``critical``, above every other finding.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from groundstation.analysis.fields import message_field
from groundstation.analysis.vibration import VIBE_BAD_M_S2, VIBE_FINE_M_S2, VibrationSummary
from groundstation.autopilot.agreement import pitch_roll_rad
from groundstation.autopilot.messages import ALARM_SEVERITIES, MESSAGE_KIND
from groundstation.autopilot.modes import event_time_s, mode_spans
from groundstation.estimation.evaluation import inclination_error_rad
from groundstation.estimation.tilt import wrap_pi
from groundstation.session_parts.clock import DISCONTINUITIES
from groundstation.session.product import ONBOARD, SessionData

SEVERITIES = ("critical", "high", "medium", "low")  # the order findings are listed in
DISAGREEMENT_DEG = 10.0  # a host estimator this far from the reference in pitch or roll: a spike worth a look
LINK_LOSS_HIGH, LINK_LOSS_MEDIUM = 0.05, 0.01  # of the frames sent (a 5 % loss makes the plots visibly gappy)
SAG_HIGH, SAG_MEDIUM = 0.20, 0.10  # battery voltage drop from its resting value, as a fraction of it
REST_S = 5.0  # the battery's resting voltage: the median over the session's first seconds
BATTERY_COLUMN = re.compile(r"^(battery|voltage|volt)(_battery)?_(m?V)$", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class Finding:
    severity: str  # one of SEVERITIES
    kind: str  # "vibration", "vibration_peak", "disagreement", "link_loss", "reboot", "battery_sag", "autopilot_message",
    # "damage", and the incidents' (``INCIDENT_TEXTS``, "brownout", "power", "clipping", "ekf_variance", "compass")
    title: str
    detail: str = ""
    t_s: float | None = None  # session time it points at, when it has one
    values: dict = dataclasses.field(default_factory=dict)  # its figures, by name with units


def findings(data: SessionData, vibration: VibrationSummary | None) -> list[Finding]:
    """Every finding, the most severe first (in time order within a severity)."""
    found = [*damage(data), *reboots(data), *incidents(data), *autopilot_messages(data), *link_loss(data), *battery_sag(data),
             *disagreement(data), *(vibration_findings(vibration) if vibration is not None else [])]
    return sorted(found, key=lambda f: (SEVERITIES.index(f.severity), f.t_s if f.t_s is not None else -1.0))


def damage(data: SessionData) -> list[Finding]:
    return [Finding("medium", "damage", "the file is damaged or incomplete", text) for text in data.damage]


def reboots(data: SessionData) -> list[Finding]:
    out = []
    for e in data.events:
        if e.get("kind") in DISCONTINUITIES:
            what = "the board restarted (its clock went back)" if e["kind"] == "device_reset" else "the board's clock jumped"
            t = event_time_s(e)
            out.append(Finding("high", "reboot", f"{what} at {t:.1f} s", str(e.get("message") or ""), t))
    return out


def autopilot_messages(data: SessionData) -> list[Finding]:
    """The autopilot's alarms and warnings that no incident explains (``incident_of``)."""
    out = []
    for e in data.events:
        if e.get("kind") == MESSAGE_KIND and e.get("severity") in (*ALARM_SEVERITIES, "WARNING") and incident_of(e) is None:
            severity = "high" if e["severity"] in ALARM_SEVERITIES else "medium"
            t = event_time_s(e)
            out.append(Finding(severity, "autopilot_message", f"autopilot {e['severity'].lower()} at {t:.1f} s: {e['message']}",
                               str(e.get("source") or ""), t))
    return out


def link_loss(data: SessionData) -> list[Finding]:
    if data.link is None:
        return []
    c = data.link.counters
    sent = c.get("frames", 0) + c.get("frames_lost", 0)
    if not sent or not c.get("frames_lost"):
        return []
    share = data.link_loss_pct() / 100.0  # the one figure every place gives (``session_parts.figures``)
    severity = "high" if share >= LINK_LOSS_HIGH else "medium" if share >= LINK_LOSS_MEDIUM else "low"
    per = data.link.per_second
    worst = int(np.argmax(per["frames_lost"])) if len(per.get("frames_lost", ())) else None
    when = f"; worst second at {per['t_s'][worst]:.0f} s ({int(per['frames_lost'][worst])} lost)" if worst is not None else ""
    return [Finding(severity, "link_loss", f"the link lost {c['frames_lost']} of {sent} frames ({100 * share:.1f} %)",
                    f"CRC errors {c.get('crc_errors', 0)}, bytes skipped {c.get('bytes_skipped', 0)}{when}",
                    None if worst is None else float(per["t_s"][worst]), {"lost_share": share})]


def battery_sag(data: SessionData) -> list[Finding]:
    """The deepest drop of the battery voltage below its resting value (the median of the first
    ``REST_S`` seconds), per battery column; under load a pack sags and recovers, an ageing or
    undersized one sags further."""
    out = []
    for table, columns in data.tables.items():
        for name, values in columns.items():
            match = BATTERY_COLUMN.match(name)
            t = columns["time_s"]
            volts = np.asarray(values, dtype=float) / (1000.0 if match and match.group(3) == "mV" else 1.0)
            ok = np.isfinite(volts) & (volts > 0.5) & np.isfinite(t) if match else None
            if ok is None or ok.sum() < 3:
                continue
            t, volts = t[ok], volts[ok]
            rest = float(np.median(volts[t <= t[0] + REST_S]))
            low = int(np.argmin(volts))
            sag = (rest - volts[low]) / rest
            if sag >= SAG_MEDIUM:
                out.append(Finding("high" if sag >= SAG_HIGH else "medium", "battery_sag",
                                   f"battery sagged from {rest:.2f} V to {volts[low]:.2f} V ({100 * sag:.0f} %) at {t[low]:.1f} s",
                                   f"{table}.{name}", float(t[low]), {"sag": sag}))
    return out


def disagreement(data: SessionData) -> list[Finding]:
    """Stretches where a host estimator is more than ``DISAGREEMENT_DEG`` from the reference: in
    inclination from the truth where the session has it (the evaluation's error), else in pitch or
    roll from the onboard estimate (``autopilot.agreement``'s difference)."""
    if not data.estimated or (data.true_q is None and not data.has_onboard()):
        return []
    against = "the truth" if data.true_q is not None else "the onboard estimate"
    t = data.time_s
    out = []
    for name, diff in differences_deg(data).items():
        over = np.nan_to_num(diff, nan=0.0) > DISAGREEMENT_DEG
        if not over.any():
            continue
        starts = np.flatnonzero(over & ~np.r_[False, over[:-1]])
        worst = int(np.argmax(np.where(over, diff, -np.inf)))
        out.append(Finding("medium", "disagreement",
                           f"{name} differs from {against} by more than {DISAGREEMENT_DEG:g}° in {len(starts)} stretch(es)",
                           f"{over.mean() * 100:.1f} % of the samples; worst {diff[worst]:.1f}° at {t[worst]:.1f} s",
                           float(t[worst]), {"worst_deg": float(diff[worst])}))
    return out


def differences_deg(data: SessionData) -> dict[str, np.ndarray]:
    """Per host estimator, on the sample rows: its inclination error against the truth, or else the
    larger of its pitch and roll differences from the onboard estimate; NaN where the reference is."""
    if data.true_q is not None:
        return {name: np.degrees(inclination_error_rad(data.quaternion(name), data.true_q, data.true_frame))
                for name in data.estimated}
    ref_pitch, ref_roll = pitch_roll_rad(data.quaternion(ONBOARD))
    out = {}
    for name in data.estimated:
        pitch, roll = pitch_roll_rad(data.quaternion(name))
        out[name] = np.degrees(np.fmax(np.abs(pitch - ref_pitch), np.abs(wrap_pi(roll - ref_roll))))
    return out


def vibration_findings(v: VibrationSummary) -> list[Finding]:
    out = []
    accel = {axis: level for axis, level in v.levels.get("accel", {}).items() if level is not None}  # None: sampled too slowly
    if accel:
        axis, level = max(accel.items(), key=lambda item: item[1])
        if level >= VIBE_FINE_M_S2:
            out.append(Finding("high" if level >= VIBE_BAD_M_S2 else "medium", "vibration",
                               f"high vibration: {level:.1f} m/s² RMS above 5 Hz on {axis}",
                               f"ArduPilot: normally fine below {VIBE_FINE_M_S2:g}, a problem above {VIBE_BAD_M_S2:g} m/s²",
                               values={"level_m_s2": level}))
    logged = (v.clipping or {}).get("imus", {})  # the autopilot's own VIBE: its accelerometer RMS above 5 Hz at full rate
    vibe = [(e[f"max_vibe_{a}_m_s2"], imu, a) for imu, e in logged.items() for a in "xyz" if f"max_vibe_{a}_m_s2" in e]
    if vibe and max(vibe)[0] >= VIBE_FINE_M_S2:
        level, imu, axis = max(vibe)
        out.append(Finding("high" if level >= VIBE_BAD_M_S2 else "medium", "vibration",
                           f"high vibration: the autopilot logged VIBE up to {level:.1f} m/s² (IMU {imu}, {axis})",
                           f"ArduPilot: normally fine below {VIBE_FINE_M_S2:g}, a problem above {VIBE_BAD_M_S2:g} m/s²",
                           values={"level_m_s2": level}))
    if v.peaks:
        p = max(v.peaks, key=lambda peak: peak.amplitude)
        out.append(Finding("low", "vibration_peak", f"vibration peak at {p.frequency_hz:.1f} Hz ({p.sensor} {p.axis}"
                           f"{', ' + p.label if p.label else ''})", v.notch.get("text", ""),
                           values={"frequency_hz": p.frequency_hz, "amplitude": p.amplitude}))
    return out


# -- incidents -------------------------------------------------------------------------------------

INCIDENT_JOIN_S = 5.0  # evidence of one kind this close to the last is the same incident
# What the autopilot says of an incident, in any of its texts: MAVLink STATUSTEXT, DataFlash MSG, ERR
# ("<subsystem>: error <code>", ``messages.ERROR_SUBSYSTEMS``; code 0, "resolved", is no incident) and EV
# (``messages.LOG_EVENTS``). Wording from ArduPilot: crash_check.cpp ("Crash: Disarming"), the failsafes'
# texts, AP_GPS ("GPS Glitch"), EKF ("EKF variance"). (kind, severity, what, pattern), matched without case.
INCIDENT_TEXTS = tuple((kind, severity, what, re.compile(pattern, re.IGNORECASE)) for kind, severity, what, pattern in (
    ("crash", "critical", "crash", r"^CRASH_CHECK: error|^crash: |crash detected|parachute released"),
    ("thrust_loss", "high", "potential thrust loss", r"^THRUST_LOSS_CHECK: error|thrust loss"),
    ("emergency_stop", "high", "motors emergency-stopped",
     r"^MOTORS_EMERGENCY_STOPPED$|MotorEStop HIGH|emergency stop(ped)?$|kill[- ]switch (engaged|on)"),
    ("failsafe", "high", "radio failsafe", r"^FAILSAFE_RADIO: error|radio failsafe|RC failsafe|RC lost"),
    ("failsafe", "high", "battery failsafe", r"^FAILSAFE_BATT: error|battery failsafe|battery \d* ?is (low|critical)|(low|critical|dangerous|emergency) battery"),
    ("failsafe", "high", "EKF failsafe", r"^(EKFCHECK|FAILSAFE_EKFINAV): error|EKF failsafe|EKF variance"),
    ("failsafe", "high", "GCS failsafe", r"^FAILSAFE_GCS: error|GCS failsafe"),
    ("failsafe", "high", "GPS failsafe", r"^FAILSAFE_GPS: error|GPS failsafe"),
    ("failsafe", "high", "vibration failsafe", r"^FAILSAFE_VIBE: error|vibration compensation"),
    ("gps_glitch", "medium", "GPS glitch", r"^GPS: error|GPS glitch|^LOST_GPS$"),
    ("compass", "medium", "compass error", r"^COMPASS: error|compass variance|mag anomaly|compass.* inconsistent"),
))  # fmt: skip
CRASH_ANGLE_DEG, CRASH_TRIGGER_S = 30.0, 2.0  # ArduCopter's crash check: attitude this far from its demand this long
BROWNOUT_V, BROWNOUT_HIGH_V = 4.5, 4.3  # board supply (POWR.Vcc); ArduPilot's BRD_VBUS_MIN default 4.3 V
OVERCURRENT_FLAGS = {8: "peripheral overcurrent", 16: "high-power peripheral overcurrent"}  # MAV_POWER_STATUS bits
POWER_TABLES = {"powr": ("Vcc", "Flags", 1.0), "power_status": ("Vcc", "flags", 1e-3)}  # table: (supply, flags, V per unit)
EKF_VARIANCE_HIGH, EKF_VARIANCE_MEDIUM = 0.8, 0.5  # FS_EKF_THRESH's default; the GCSs' amber
# The EKF's normalised innovation variances: a log's table (by name) -> {field: what it measures}. EKF3's
# XKF4 and EKF2's NKF4 (one per core), MAVLink's EKF_STATUS_REPORT (live and in a .tlog).
EKF_VARIANCES = ((re.compile(r"^[xn]kf4(_\d+)?$"), {"SV": "velocity", "SP": "position", "SH": "height", "SM": "magnetometer",
                                                    "SVT": "airspeed"}),
                 (re.compile(r"^ekf_status_report$"), {"velocity_variance": "velocity", "pos_horiz_variance": "position",
                                                       "pos_vert_variance": "height", "compass_variance": "magnetometer",
                                                       "terrain_alt_variance": "terrain height"}))
# The accelerometers' clip counters (since boot): DataFlash VIBE (per IMU), MAVLink VIBRATION.
CLIP_COUNTERS = ((re.compile(r"^vibe(_\d+)?$"), ("Clip", "Clip0", "Clip1", "Clip2")),
                 (re.compile(r"^vibration$"), ("clipping_0", "clipping_1", "clipping_2")))
MAG_INTERFERENCE = 0.3  # of the field's usual strength: ArduPilot's COMPASS_MOT calibration treats 30 % as bad interference


@dataclasses.dataclass(frozen=True)
class Evidence:
    kind: str
    severity: str
    what: str
    t_s: float
    said: str  # the log's own words or figures


def incident_of(event: dict) -> tuple | None:
    """The ``INCIDENT_TEXTS`` entry an autopilot message event is evidence of, else None."""
    if event.get("kind") != MESSAGE_KIND:
        return None
    return next((entry for entry in INCIDENT_TEXTS if entry[3].search(str(event.get("message", "")))), None)


def incidents(data: SessionData) -> list[Finding]:
    """Every incident, its evidence joined (the module's rule), titled with the time, mode and arming."""
    evidence = sorted([*_said(data), *_crash_attitude(data), *_power(data), *_clipping(data), *_ekf_variance(data),
                       *_compass_field(data)], key=lambda e: e.t_s)  # fmt: skip
    groups: list[list[Evidence]] = []
    for e in evidence:
        same = next((g for g in reversed(groups) if (g[0].kind, g[0].what) == (e.kind, e.what)), None)
        if same is not None and e.t_s - same[-1].t_s <= INCIDENT_JOIN_S:
            same.append(e)
        else:
            groups.append([e])
    spans = mode_spans(data.events, float(data.time_s[-1]) if len(data.time_s) else 0.0)
    out = []
    for group in groups:
        first = group[0]
        severity = min((e.severity for e in group), key=SEVERITIES.index)
        state = next((f" ({'armed' if s.armed else 'disarmed' if s.armed is not None else 'arming unknown'}, {s.mode})"
                      for s in spans if s.start_s <= first.t_s <= s.end_s), "")
        out.append(Finding(severity, first.kind, f"{first.what} at {first.t_s:.1f} s{state}",
                           "; ".join(dict.fromkeys(f"{e.said} at {e.t_s:.2f} s" for e in group)), first.t_s))
    return out


def _said(data: SessionData) -> list[Evidence]:
    out = []
    for e in data.events:
        if (entry := incident_of(e)) is not None:
            kind, severity, what, _ = entry
            out.append(Evidence(kind, severity, what, event_time_s(e), f"{e.get('source') or 'autopilot'} \"{e['message']}\""))
    return out


def _crash_attitude(data: SessionData) -> list[Evidence]:
    """ArduCopter's crash check on its logged ``ATT``: roll or pitch more than ``CRASH_ANGLE_DEG`` from the
    demand for ``CRASH_TRIGGER_S``; the evidence at the moment the check would fire."""
    att = data.tables.get("att")
    columns = {name: message_field(att, name) for name in ("DesRoll", "Roll", "DesPitch", "Pitch")} if att else {}
    if not columns or any(v is None for v in columns.values()):
        return []
    t = att["time_s"]
    error = np.fmax(np.abs(columns["DesRoll"] - columns["Roll"]), np.abs(columns["DesPitch"] - columns["Pitch"]))
    over = np.nan_to_num(error) > CRASH_ANGLE_DEG
    starts = np.flatnonzero(over & ~np.r_[False, over[:-1]])
    ends = np.flatnonzero(over & ~np.r_[over[1:], False])
    out = []
    for start, end in zip(starts, ends):
        fires = np.flatnonzero(t[start : end + 1] >= t[start] + CRASH_TRIGGER_S)
        if len(fires):
            at = start + int(fires[0])
            out.append(Evidence("crash", "critical", "crash", float(t[at]),
                                f"ATT {error[at]:.0f}° from its demand since {t[start]:.2f} s (crash check: {CRASH_ANGLE_DEG:g}° for {CRASH_TRIGGER_S:g} s)"))
    return out


def _power(data: SessionData) -> list[Evidence]:
    """The board's supply below ``BROWNOUT_V`` (a brownout resets the board), and overcurrent flags: DataFlash
    ``POWR`` or MAVLink ``POWER_STATUS`` (``POWER_TABLES``; the flags are MAV_POWER_STATUS in both)."""
    out = []
    for name, (vcc_field, flags_field, volts_per_unit) in POWER_TABLES.items():
        table = data.tables.get(name)
        if not table or not len(table.get("time_s", ())):
            continue
        t, said = table["time_s"], name.upper()
        vcc = message_field(table, vcc_field)
        vcc = None if vcc is None else vcc * volts_per_unit
        if vcc is not None and (low := np.flatnonzero(vcc < BROWNOUT_V)).size:
            lowest = low[np.argmin(vcc[low])]
            out.append(Evidence("brownout", "high" if vcc[lowest] < BROWNOUT_HIGH_V else "medium", "brownout: board supply low",
                                float(t[low[0]]), f"{said}.{vcc_field} {vcc[low[0]]:.2f} V (lowest {vcc[lowest]:.2f} V at {t[lowest]:.2f} s)"))
        flags = message_field(table, flags_field)
        for bit, what in OVERCURRENT_FLAGS.items():
            if flags is not None and (hit := np.flatnonzero(np.nan_to_num(flags).astype(int) & bit)).size:
                out.append(Evidence("power", "high", f"power: {what}", float(t[hit[0]]),
                                    f"{said}.{flags_field} {int(flags[hit[0]])} (bit {bit})"))
    return out


def _clipping(data: SessionData) -> list[Evidence]:
    """An accelerometer's clip counter (``CLIP_COUNTERS``, counting since boot) rising: samples beyond its range lost."""
    out = []
    for name, table, fields in ((n, data.tables[n], fields) for pattern, fields in CLIP_COUNTERS
                                for n in sorted(data.tables) if pattern.match(n)):
        for field in fields:
            clips = message_field(table, field)
            if clips is None or not (rise := np.flatnonzero(np.diff(np.nan_to_num(clips)) > 0)).size:
                continue
            at = rise[0] + 1
            out.append(Evidence("clipping", "high", "the accelerometer clipped", float(table["time_s"][at]),
                                f"{name.upper()}.{field} {clips[at - 1]:.0f} -> {clips[at]:.0f} (by the end {np.nanmax(clips):.0f})"))
    return out


def _ekf_variance(data: SessionData) -> list[Evidence]:
    """The EKF's normalised innovation variances (``EKF_VARIANCES``) at the failsafe's threshold or the GCSs'
    amber: each variance's first time above the higher level it reaches."""
    out = []
    for name, table, fields in ((n, data.tables[n], fields) for pattern, fields in EKF_VARIANCES
                                for n in sorted(data.tables) if pattern.match(n)):
        for field, what in fields.items():
            values = message_field(table, field)
            if values is None:
                continue
            for level, severity in ((EKF_VARIANCE_HIGH, "high"), (EKF_VARIANCE_MEDIUM, "medium")):
                if (above := np.flatnonzero(np.nan_to_num(values) > level)).size:
                    at = above[0]
                    out.append(Evidence("ekf_variance", severity, f"EKF {what} variance high", float(table["time_s"][at]),
                                        f"{name.upper()}.{field} {values[at]:.2f} (above {level:g}; most {np.nanmax(values):.2f})"))
                    break
    return out


def _compass_field(data: SessionData) -> list[Evidence]:
    """The magnetic field's strength straying from its own median by more than ``MAG_INTERFERENCE`` (the
    Earth's field is the same all flight; motors, wiring or metal near the compass change it); a constant
    strength of any size is a scale, not interference."""
    mag = data.tables.get("mag_raw")
    if not mag or not len(mag.get("time_s", ())):
        return []
    strength = np.sqrt(sum(np.asarray(mag[f"mag_{a}_uT"], dtype=float) ** 2 for a in "xyz"))
    usual = float(np.nanmedian(strength))
    off = np.abs(strength - usual) / usual if usual > 0 else np.zeros_like(strength)
    outside = np.flatnonzero(np.nan_to_num(off) > MAG_INTERFERENCE)
    if not outside.size:
        return []
    at, worst = outside[0], int(np.nanargmax(off))
    return [Evidence("compass", "medium", "compass interference", float(mag["time_s"][at]),
                     f"magnetic field {strength[at]:.0f} µT against its usual {usual:.0f} µT (most {100 * off[worst]:.0f} % off "
                     f"at {mag['time_s'][worst]:.2f} s); {outside.size} of {strength.size} readings over {100 * MAG_INTERFERENCE:g} % off")]

"""What a flight report points out first: findings read off a session's product, ranked by severity.

Each rule reads what the product already holds (its events, tables, link figures), the vibration
summary (``analysis.vibration``) and the estimators' agreement (``autopilot.agreement``); none
recomputes them. Thresholds are named here with where they come from.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np

from groundstation.analysis.vibration import VIBE_BAD_M_S2, VIBE_FINE_M_S2, VibrationSummary
from groundstation.autopilot.agreement import pitch_roll_rad
from groundstation.autopilot.messages import ALARM_SEVERITIES, MESSAGE_KIND
from groundstation.autopilot.modes import event_time_s
from groundstation.estimation.evaluation import inclination_error_rad
from groundstation.estimation.tilt import wrap_pi
from groundstation.session.clock import DISCONTINUITIES
from groundstation.session.product import ONBOARD, SessionData

SEVERITIES = ("high", "medium", "low")  # the order findings are listed in
DISAGREEMENT_DEG = 10.0  # a host estimator this far from the reference in pitch or roll: a spike worth a look
LINK_LOSS_HIGH, LINK_LOSS_MEDIUM = 0.05, 0.01  # of the frames sent (a 5 % loss makes the plots visibly gappy)
SAG_HIGH, SAG_MEDIUM = 0.20, 0.10  # battery voltage drop from its resting value, as a fraction of it
REST_S = 5.0  # the battery's resting voltage: the median over the session's first seconds
BATTERY_COLUMN = re.compile(r"^(battery|voltage|volt)(_battery)?_(m?V)$", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class Finding:
    severity: str  # one of SEVERITIES
    kind: str  # "vibration", "vibration_peak", "clipping", "disagreement", "link_loss", "reboot", "battery_sag", "autopilot_message", "damage"
    title: str
    detail: str = ""
    t_s: float | None = None  # session time it points at, when it has one
    values: dict = dataclasses.field(default_factory=dict)  # its figures, by name with units


def findings(data: SessionData, vibration: VibrationSummary | None) -> list[Finding]:
    """Every finding, the most severe first (in time order within a severity)."""
    found = [*damage(data), *reboots(data), *autopilot_messages(data), *link_loss(data), *battery_sag(data),
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
    out = []
    for e in data.events:
        if e.get("kind") == MESSAGE_KIND and e.get("severity") in (*ALARM_SEVERITIES, "WARNING"):
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
    share = c["frames_lost"] / sent
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
    clips = sum(e.get("clips", 0) for e in logged.values())
    if clips:
        out.append(Finding("high", "clipping", f"the accelerometer clipped {clips} times", "samples beyond its range are lost"))
    if v.peaks:
        p = max(v.peaks, key=lambda peak: peak.amplitude)
        out.append(Finding("low", "vibration_peak", f"vibration peak at {p.frequency_hz:.1f} Hz ({p.sensor} {p.axis}"
                           f"{', ' + p.label if p.label else ''})", v.notch.get("text", ""),
                           values={"frequency_hz": p.frequency_hz, "amplitude": p.amplitude}))
    return out

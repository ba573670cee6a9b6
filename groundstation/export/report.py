"""A flight report: one self-contained HTML page about a session, whatever made it (a recording, a
dataset CSV, a ``.tlog``, ``.bin`` or ``.ulg``).

The page opens offline and alone: its figures are inline SVG (``report_figures``), its style is in
the page, it has no script and no external address. Its sections: the flight (vehicle, firmware,
duration, modes), the findings ranked by severity (``report_findings``), attitude (the host
estimators against the truth or the onboard estimate: the evaluation's or the agreement's table, and
a plot, each estimator in its colour of the app's palette), an autopilot's controller, battery, GPS and outputs
(``autopilot.sections``), vibration (``analysis.vibration``: spectrum, peaks, levels, clipping, the notch
suggestion, and what that notch would do: ``analysis.whatif``'s spectra before and after, its Bode view
and the attitude difference where the IMU carries it), the link, and the events with the autopilot's messages.

It reads the product only (``SessionData``), as every export does: the command and the window hand
it a session they loaded.
"""

from __future__ import annotations

import datetime
import math
import re
from pathlib import Path

import numpy as np

from groundstation import __version__, quaternion
from groundstation.analysis.vibration import UNITS, VibrationError, VibrationSummary, vibration_summary
from groundstation.analysis.whatif import LAG_AT_HZ, what_if
from groundstation.autopilot.agreement import onboard_agreement
from groundstation.autopilot.messages import ALARM_SEVERITIES, MESSAGE_KIND, PARAMETER_KIND
from groundstation.autopilot.imu_rate import IMU_RATE
from groundstation.autopilot.modes import STATUS_KIND, event_time_s, mode_spans
from groundstation.autopilot.sections import pages_of
from groundstation.errors import UserError
from groundstation.estimation import colour_of, label
from groundstation.estimation.evaluation import truth_in_ned
from groundstation.export.files import atomic_output
from groundstation.export.report_figures import escaped, line_plot
from groundstation.export.report_findings import Finding, differences_deg, findings
from groundstation.palette import ONBOARD_COLOUR, TRUTH_COLOUR
from groundstation.session_parts.clock import DISCONTINUITIES
from groundstation.session.product import ONBOARD, SessionData

MAX_EVENTS = 300  # rows of the events table; the rest are counted
MAX_FINDINGS = 100  # findings listed, the most severe first; the rest are counted (one log said 60,000)
MAX_PLOTTED_ESTIMATORS = 4
FIRMWARE = re.compile(r"\b(ArduCopter|ArduPlane|ArduRover|ArduSub|Rover|APM:\w+|PX4|Blimp|AntennaTracker)\b[^\n]*?\bV?\d+\.\d+[\w.\-]*",
                      re.IGNORECASE)
STYLE = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 800px; color: #222; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; margin-top: 1.6em; }
table { border-collapse: collapse; margin: 0.5em 0; font-size: 0.9em; }
td, th { border: 1px solid #ccc; padding: 2px 8px; text-align: left; } th { background: #f0f0f0; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
.finding { margin: 0.3em 0; padding: 0.3em 0.6em; border-left: 6px solid #999; background: #fafafa; list-style: none; }
.finding.critical { border-color: #600; background: #fee; } .finding.high { border-color: #c00; } .finding.medium { border-color: #e90; } .finding.low { border-color: #39c; }
.sev { font-weight: bold; text-transform: uppercase; font-size: 0.8em; margin-right: 0.5em; }
.detail { color: #555; font-size: 0.9em; } .warn { color: #a00; } ul.findings { padding-left: 0; }
tr.alarm td { color: #a00; }
"""


NOT_RECORDED = "not recorded"  # a vehicle or firmware the session does not name


def write_report(data: SessionData, out, file_name: str = "", overwrite: bool = False) -> Path:
    """The report of ``data`` (computed from the file ``file_name``) written to ``out`` (``.html``),
    whole or not at all."""
    out = Path(out)
    if out.suffix.lower() not in (".html", ".htm"):
        raise UserError(f"{out}: a report is an HTML page; name it .html")
    page = report_html(data, file_name)
    with atomic_output(out, overwrite) as temporary:
        try:
            Path(temporary).write_text(page, encoding="utf-8")
        except OSError as error:
            raise UserError(f"cannot write {out}: {error.strerror}") from None
    return out


def report_html(data: SessionData, file_name: str = "") -> str:
    vibration, vibration_note = vibration_of(data)
    found = findings(data, vibration)
    title = f"Flight report: {file_name or data.metadata.get('source', 'session')}"
    parts = [f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{escaped(title)}</title>"
             f"<style>{STYLE}</style></head><body>", f"<h1>{escaped(title)}</h1>",
             f"<p class=\"detail\">made by groundstation {__version__} on {datetime.date.today().isoformat()}</p>",
             flight_section(data, file_name), findings_section(found), attitude_section(data), controller_section(data),
             vibration_section(vibration, vibration_note), what_if_section(data, vibration), link_section(data),
             events_section(data), "</body></html>"]
    return "\n".join(parts)


def vibration_of(data: SessionData) -> tuple[VibrationSummary | None, str]:
    try:
        return vibration_summary(data), ""
    except VibrationError as error:
        return None, str(error)


def _table(header: list[str], rows: list[list], numeric_from: int = 1, row_class=None) -> str:
    head = "".join(f"<th>{escaped(h)}</th>" for h in header)
    body = []
    for i, row in enumerate(rows):
        cells = "".join(f"<td class=\"n\">{escaped(c)}</td>" if j >= numeric_from else f"<td>{escaped(c)}</td>" for j, c in enumerate(row))
        css = f" class=\"{row_class(i)}\"" if row_class and row_class(i) else ""
        body.append(f"<tr{css}>{cells}</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def firmware(data: SessionData) -> str:
    """The firmware as the session says it: the recording's header, else the autopilot's own words
    (ArduPilot says "ArduCopter V4.3.6 (…)" at boot, in its messages)."""
    for key in ("firmware", "firmware_version", "app_version"):
        if data.metadata.get(key) and key != "app_version":
            return str(data.metadata[key])
    for e in data.events:
        if e.get("kind") == MESSAGE_KIND and (m := FIRMWARE.search(str(e.get("message", "")))):
            return m.group(0)
    if data.config:
        return f"this project's firmware, protocol {data.metadata.get('protocol_version', '?')}"
    return NOT_RECORDED


def vehicle(data: SessionData) -> str:
    meta = data.metadata
    if meta.get("autopilot"):
        return str(meta["autopilot"])
    if data.protocol == "gs":
        return "this project's aircraft" + (f" (simulated, scenario '{meta['scenario']}')" if meta.get("scenario") else "")
    return NOT_RECORDED


def flight_section(data: SessionData, file_name: str) -> str:
    meta = data.metadata
    rows = [["file", file_name or "-"], ["source", meta.get("source", "")], ["vehicle", vehicle(data)],
            ["firmware", firmware(data)], ["duration", f"{data.duration_s():.1f} s"],
            ["IMU samples", f"{len(data.tables['imu']['time_s'])}" + (f" at {rate:.1f} Hz" if math.isfinite(rate := data.imu_rate_hz()) else "")],
            ["link loss", f"{loss:.1f} %" if math.isfinite(loss := data.link_loss_pct()) else "no link decoded"],
            ["host estimators", ", ".join(data.estimated) or "none (no IMU samples)"],
            ["reference", "truth" if data.true_q is not None else "the onboard estimate" if data.has_onboard() else "none"]]
    if data.parameters:
        rows.append(["parameters", f"{len(data.parameters)} recorded"])
    out = ["<h2>Flight</h2>", _table(["", ""], rows, numeric_from=2)]
    spans = mode_spans(data.events, float(data.time_s[-1]) if len(data.time_s) else 0.0)
    if spans:
        out.append("<h3>Modes</h3>")
        out.append(_table(["mode", "armed", "from (s)", "to (s)", "for (s)"],
                          [[s.mode, {True: "armed", False: "disarmed", None: "?"}[s.armed], f"{s.start_s:.1f}", f"{s.end_s:.1f}",
                            f"{s.end_s - s.start_s:.1f}"] for s in spans], numeric_from=2))
    else:
        out.append("<p>Modes: the session reported none.</p>")
    if data.warnings:
        out.append("<h3>What the file lost, and warnings</h3><ul>" + "".join(f"<li class=\"warn\">{escaped(w)}</li>" for w in data.warnings) + "</ul>")
    return "\n".join(out)


def data_attribute(name: str) -> str:
    """A figure's name as an HTML data- attribute: lower case, every run of other characters than letters and
    digits one hyphen (``level_m_s2`` -> ``data-level-m-s2``, ``gap (s)`` -> ``data-gap-s``), so that no name
    breaks the tag it is written into."""
    return "data-" + re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")


def findings_section(found: list[Finding]) -> str:
    if not found:
        return "<h2>Findings</h2><p>Nothing to point out.</p>"
    items = []
    for f in found[:MAX_FINDINGS]:
        values = "".join(f" {data_attribute(k)}=\"{v:.6g}\"" for k, v in f.values.items())
        when = f" data-t-s=\"{f.t_s:.3f}\"" if f.t_s is not None else ""
        items.append(f"<li class=\"finding {f.severity}\" data-kind=\"{f.kind}\"{when}{values}><span class=\"sev\">{f.severity}</span>"
                     f"{escaped(f.title)}" + (f"<div class=\"detail\">{escaped(f.detail)}</div>" if f.detail else "") + "</li>")
    rest = f"<p>… and {len(found) - MAX_FINDINGS} more findings.</p>" if len(found) > MAX_FINDINGS else ""
    return "<h2>Findings</h2><ul class=\"findings\">" + "".join(items) + "</ul>" + rest


def attitude_section(data: SessionData) -> str:
    out = ["<h2>Attitude</h2>"]
    if data.true_q is not None and data.estimated:
        try:
            scores = data.evaluate()
        except UserError as error:
            scores, out = {}, [*out, f"<p>{escaped(error)}</p>"]
        rows = [[n, f"{s['incl_rmse_deg']:.3f}", f"{s['incl_max_deg']:.3f}",
                 f"{s['heading_rmse_deg']:.3f}" if "heading_rmse_deg" in s else "-"] for n, s in scores.items()]
        out.append("<p>Against the truth (inclination: the angle between the estimated and the true down).</p>")
        out.append(_table(["estimator", "incl RMSE (°)", "incl max (°)", "heading RMSE (°)"], rows))
        reference, reference_name, reference_colour = truth_in_ned(data.true_q, data.true_frame), "truth", TRUTH_COLOUR
    elif data.has_onboard() and data.estimated:
        rows = [[n, f"{a['pitch_rms_deg']:.3f}", f"{a['pitch_max_deg']:.3f}", f"{a['roll_rms_deg']:.3f}", f"{a['roll_max_deg']:.3f}", a["rows"]]
                for n, a in onboard_agreement(data).items()]
        out.append("<p>Agreement with the onboard estimate: a difference, not an error (the onboard estimate is not truth).</p>")
        out.append(_table(["estimator", "pitch RMS (°)", "pitch max (°)", "roll RMS (°)", "roll max (°)", "rows"], rows))
        reference, reference_name, reference_colour = data.quaternion(ONBOARD), ONBOARD, ONBOARD_COLOUR
    elif data.has_onboard():
        out.append("<p>No IMU samples: the onboard estimate only.</p>")
        reference, reference_name, reference_colour = data.quaternion(ONBOARD), ONBOARD, ONBOARD_COLOUR
    else:
        return "\n".join([*out, "<p>No reference to compare the estimators with (no truth, no onboard estimate).</p>"])
    t = data.time_s
    marks = _reboot_marks(data)
    for angle, index in (("pitch", 1), ("roll", 2)):
        series = [(reference_name, t, quaternion.euler_deg(reference)[index], reference_colour, True)]
        series += [(label(n), t, quaternion.euler_deg(data.quaternion(n))[index], colour_of(n))
                   for n in data.estimated[:MAX_PLOTTED_ESTIMATORS]]
        out.append(line_plot(series, f"{angle}", "session time (s)", f"{angle} (°)", marks=marks))
    if data.estimated:
        diffs = differences_deg(data)
        y_label = "inclination error (°)" if data.true_q is not None else "max(|Δpitch|, |Δroll|) (°)"
        out.append(line_plot([(label(n), t, d, colour_of(n)) for n, d in list(diffs.items())[:MAX_PLOTTED_ESTIMATORS]],
                             f"difference from {reference_name}", "session time (s)", y_label, marks=marks))
    return "\n".join(out)


def controller_section(data: SessionData) -> str:
    """The autopilot's own figures a flyer reads in Mission Planner or Flight Review (``autopilot.sections``: the
    pages the app's Flight tab shows): desired against actual attitude and rates, battery, GPS, outputs; nothing
    for a session without them (the project's own aircraft)."""
    pages = pages_of(data.catalogue)
    if not pages:
        return ""
    out = ["<h2>Controller, battery, GPS and outputs</h2>",
           "<p>As the autopilot logged them: what its controller asked for against what it had, its battery, its GPS "
           "fix and its actuator outputs.</p>"]
    for page in pages:
        out.append(f"<h3>{escaped(page.title)}</h3>")
        for figure in page.figures:
            unit = f" ({figure.unit})" if figure.unit else ""
            out.append(line_plot([(t.label, data.tables[t.table]["time_s"], data.tables[t.table][t.column], t.colour)
                                  for t in figure.traces], f"{page.title}: {figure.title}", "session time (s)",
                                 f"{figure.title}{unit}", marks=_reboot_marks(data)))
    return "\n".join(out)


def _reboot_marks(data: SessionData) -> list[tuple[float, str]]:
    return [(event_time_s(e), "reboot" if e["kind"] == "device_reset" else "clock jump") for e in data.events if e.get("kind") in DISCONTINUITIES]


def vibration_section(v: VibrationSummary | None, note: str) -> str:
    out = ["<h2>Vibration</h2>"]
    if v is None:
        return "\n".join([*out, f"<p>No spectrum: {escaped(note)}.</p>"])
    for sensor, sp in v.spectra.items():
        series = [(f"{sensor} {a}", sp.frequency_hz, sp.amplitude[a]) for a in sp.amplitude]
        out.append(line_plot(series, f"{sensor} spectrum ('{sp.table}' at {sp.rate_hz:.0f} Hz)", "frequency (Hz)",
                             f"amplitude ({UNITS[sensor]})", log_y=True,
                             marks=[(p.frequency_hz, f"{p.frequency_hz:.1f}") for p in v.peaks if p.sensor == sensor][:3]))
    if v.peaks:
        out.append(_table(["sensor", "axis", "frequency (Hz)", "amplitude", "label"],
                          [[p.sensor, p.axis, f"{p.frequency_hz:.2f}", f"{p.amplitude:.3f} {p.unit}", p.label] for p in v.peaks],
                          numeric_from=2))
    else:
        out.append("<p>No peak stands out of the spectrum.</p>")
    out.append(_table(["sensor", "x", "y", "z", "unit"],  # a level is None where the stream is too slow for it
                      [[s, *("—" if a.get(k) is None else f"{a[k]:.3f}" for k in "xyz"), UNITS[s]] for s, a in v.levels.items()]))
    text = v.lines()
    clipping = [line for line in text if line.startswith(("VIBE", "vehicle_imu_status", "motors:"))]
    out += [f"<p>{escaped(line)}</p>" for line in clipping]
    out.append(f"<p><b>Notch suggestion:</b> {escaped(v.notch['text']) if v.notch else 'none (no peak to suggest one for)'}</p>")
    out += [f"<p class=\"warn\">{escaped(w)}</p>" for w in v.warnings]
    return "\n".join(out)


BODE_FLOOR_DB = -60.0  # a notch's centre is -inf dB: drawn at this floor
BODE_SPAN = 3.0  # the Bode plots run to this many times the filter's frequency: the attitude loop's band and the notch


def what_if_section(data: SessionData, v: VibrationSummary | None) -> str:
    """What the suggested notch would do (``analysis.whatif``), on data sampled fast enough for it; nothing
    without a suggestion."""
    if v is None or not v.notch:
        return ""
    out = ["<h3>What the suggested notch would do</h3>"]
    try:
        change = what_if(data, "notch", v.notch["frequency_hz"], v.notch["bandwidth_hz"], v.start_s, v.end_s)
    except VibrationError as error:
        return "\n".join([*out, f"<p>Not computed: {escaped(error)}.</p>"])
    for sensor, f in change.spectra.items():
        out.append(line_plot([("before", f.before.frequency_hz, f.before.total_psd), ("after", f.after.frequency_hz, f.after.total_psd)],
                             f"{sensor} spectrum before and after ('{f.table}' at {f.rate_hz:.0f} Hz)", "frequency (Hz)",
                             f"density ({UNITS[sensor]}²/Hz, x+y+z)", log_y=True,
                             marks=[] if f.peak_hz is None else [(f.peak_hz, f"{f.attenuation_db:+.1f} dB")]))
    shown = change.bode_hz <= BODE_SPAN * change.frequency_hz
    marks = [(hz, f"{hz:g} Hz") for hz in LAG_AT_HZ if hz in change.bode_hz]
    out.append(line_plot([("gain", change.bode_hz[shown], np.maximum(change.magnitude_db[shown], BODE_FLOOR_DB))],
                         f"the notch's gain (run at {change.bode_rate_hz:.0f} Hz)", "frequency (Hz)", "gain (dB)", marks=marks))
    out.append(line_plot([("phase", change.bode_hz[shown], change.phase_deg[shown])], "the notch's phase", "frequency (Hz)",
                         "phase (°; negative: lag)", marks=marks))
    lags = "".join(f" data-lag-{hz:g}-hz-deg=\"{lag:.6g}\"" for hz, lag in change.phase_lag_deg.items())
    out += [f"<p class=\"whatif\"{lags}>{escaped(line.strip())}</p>" for line in change.lines()]
    return "\n".join(out)


def link_section(data: SessionData) -> str:
    out = ["<h2>Link</h2>"]
    if data.link is None:
        return "\n".join([*out, "<p>No link was decoded: a flight log or a dataset.</p>"])
    c = data.link.counters
    out.append(_table(["counter", "value"], [[k.replace("_", " "), v] for k, v in c.items()]))
    per = data.link.per_second
    if len(per.get("t_s", ())):
        out.append(line_plot([("frames/s", per["t_s"], per["frames"]), ("lost/s", per["t_s"], per["frames_lost"])],
                             "link per second", "session time (s)", "frames", marks=_reboot_marks(data)))
    return "\n".join(out)


def events_section(data: SessionData) -> str:
    """Every event in time order but the parameter changes (counted) and the live slow-IMU warning (the
    report's warnings give the whole session's IMU rate, ``SessionData.warnings``): modes, the autopilot's
    messages, resets, warnings; alarms in red."""
    shown = sorted((e for e in data.events if e.get("kind") != PARAMETER_KIND and e.get("about") != IMU_RATE), key=event_time_s)
    changes = sum(e.get("kind") == PARAMETER_KIND for e in data.events)
    out = ["<h2>Events and messages</h2>"]
    if not shown:
        out.append("<p>The session has no events.</p>")
    else:
        rows = [[f"{event_time_s(e):.2f}", e.get("kind", ""), e.get("severity") or "", _event_text(e)] for e in shown[:MAX_EVENTS]]
        alarm = {i for i, e in enumerate(shown[:MAX_EVENTS]) if e.get("severity") in ALARM_SEVERITIES or e.get("kind") in DISCONTINUITIES}
        out.append(_table(["time (s)", "kind", "severity", "what"], rows, numeric_from=4,
                          row_class=lambda i: "alarm" if i in alarm else ""))
        if len(shown) > MAX_EVENTS:
            out.append(f"<p>… and {len(shown) - MAX_EVENTS} more events.</p>")
    if changes:
        out.append(f"<p>{changes} parameter changes (not listed).</p>")
    return "\n".join(out)


def _event_text(e: dict) -> str:
    if e.get("kind") == STATUS_KIND:
        return f"mode {e.get('mode')}" + {True: ", armed", False: ", disarmed"}.get(e.get("armed"), "")
    if e.get("message"):
        return str(e["message"])
    return ", ".join(f"{k} {v}" for k, v in e.items() if k not in ("kind", "t_s", "t_host_ns", "session_time_s"))[:200]

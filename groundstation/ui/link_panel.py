"""Link health: frames/s, loss, CRC failures, bytes/s, time since the last frame, latency; on a
MAVLink link also both radios' signal (RADIO_STATUS) and the battery (SYS_STATUS: voltage, current and
remaining; BATTERY_STATUS: the charge used) when they arrive, each figure only when the autopilot knows it.

The headline turns amber when the link degrades (losses, CRC failures, a late frame) and red when
frames stop or the port is gone. Figures of the last complete second, from the session view's link
figures and the decoder's counters.
"""

from __future__ import annotations

import math
import time

from PySide6 import QtWidgets

from groundstation.session_parts.figures import loss_pct
from groundstation.session.view import Session
from groundstation.ui.sample_streams import stream_interval_s

LATE_FRAME_S = 0.25  # 25 samples missing at 100 Hz
LATE_INTERVALS = 3  # a slower stream (an autopilot's 4 Hz) is late after three of its own intervals (issue 24, defect 6)
NO_DATA_S = 1.0
DEGRADED_LOSS_PCT = 2.0
STYLES = {
    "ok": "background:#2e7d32; color:white; padding:4px; font-weight:bold",
    "degraded": "background:#f0a000; color:black; padding:4px; font-weight:bold",
    "down": "background:#c62828; color:white; padding:4px; font-weight:bold",
    "idle": "background:#9e9e9e; color:white; padding:4px; font-weight:bold",
}
FIELDS = ("frames/s", "loss", "CRC failures", "bytes/s", "since last frame", "latency p50 / p99")
# A MAVLink session's radio and battery (session_makers/mavlink_front.py tables), shown once they have a row:
# row label -> (table, format of its last row's columns). RSSI and noise are in the radio's own units
# (SiK: about 1.9 per dB above -127 dBm), as Mission Planner and QGroundControl show them.
RADIO_FIELDS = {
    "RSSI ground / air": ("radio_status", "{rssi:.0f} / {remote_rssi:.0f}"),
    "noise ground / air": ("radio_status", "{noise:.0f} / {remote_noise:.0f}"),
    "radio rx errors": ("radio_status", "{rx_errors:.0f}"),
}
WIDEST_VALUE = "12.60 V, 35.2 A, 1250 mAh used, 100 % left"  # the battery's, the longest a row shows
BATTERY = "battery"  # its row: SYS_STATUS, with what BATTERY_STATUS adds when the autopilot sends it
NOT_REPORTED = "not reported"


def link_figures(session: Session, now_ns: int) -> dict[str, float]:
    link = session.view.link
    counters = session.view.counters()
    with session.lock:
        last = link.per_second.tail(1)
        clock = link.clock()
    frames, lost, crc = (last[0][1], last[0][4], last[0][3]) if len(last) else (math.nan, math.nan, math.nan)
    bytes_per_s = last[0][2] if len(last) else math.nan
    # The statistics close a second only when a chunk arrives after it: with nothing arriving (a port
    # gone, a silent link) the last row would stand for ever. No chunk in the last second: none came.
    if link.last_chunk_ns is not None and now_ns - link.last_chunk_ns >= NO_DATA_S * 1e9:
        frames = bytes_per_s = crc = lost = 0.0
    return {
        "frames_per_s": frames,
        "bytes_per_s": bytes_per_s,
        "loss_pct": loss_pct(counters["frames"], counters["frames_lost"]),  # the session's, as every place says it
        "loss_now_pct": loss_pct(frames, lost) if math.isfinite(frames + lost) else math.nan,  # the last second's
        "crc_per_s": crc,
        "crc_total": counters["crc_errors"],
        "lost_total": counters["frames_lost"],
        "since_last_frame_s": link.since_last_frame_s(now_ns),
        "late_after_s": late_after_s(stream_interval_s(session.view)),
        **clock,
    }


def late_after_s(interval_s: float) -> float:
    """How long without a frame makes the link late: ``LATE_FRAME_S``, or ``LATE_INTERVALS`` of the
    samples' own interval on a slower stream (NaN: not known yet)."""
    return LATE_INTERVALS * interval_s if LATE_INTERVALS * interval_s > LATE_FRAME_S else LATE_FRAME_S


def link_state(session: Session, figures: dict[str, float]) -> tuple[str, str]:
    """(style key, headline)."""
    if not session.connected:
        return "down", "PORT GONE — reconnecting…"
    if not session.running:
        return "idle", "STOPPED"
    since = figures["since_last_frame_s"]
    if since >= NO_DATA_S:
        return "down", "NO DATA" if math.isinf(since) else f"NO DATA for {since:.0f} s"
    if since >= figures["late_after_s"] or figures["loss_now_pct"] >= DEGRADED_LOSS_PCT or figures["crc_per_s"] > 0:
        return "degraded", "DEGRADED"
    return "ok", "LINK OK"


def radio_figures(session: Session) -> dict[str, str]:
    """RADIO_FIELDS' text and the battery's for the tables that have a row (none on the project's own link)."""
    tables = session.view.tables
    with session.lock:
        last = {name: dict(zip(tables[name].columns, rows[0].tolist()))
                for name in {*(t for t, _ in RADIO_FIELDS.values()), "sys_status", "battery_status"}
                if name in tables and len(rows := tables[name].tail(1))}
    shown = {label: text.format(**last[name]) for label, (name, text) in RADIO_FIELDS.items() if name in last}
    if "sys_status" in last:
        shown[BATTERY] = battery_text(last["sys_status"], last.get("battery_status"))
    return shown


def battery_text(status: dict[str, float], detail: dict[str, float] | None = None) -> str:
    """Voltage, current, charge used and remaining, each only when known: SYS_STATUS says unknown
    with UINT16_MAX and -1 (NaN in the table), and an autopilot without a battery monitor sends 0 V,
    which no battery powering it can read. The charge used comes from BATTERY_STATUS (-1: unknown)."""
    used = (detail or {}).get("current_consumed_mAh", math.nan)
    parts = [f"{status['voltage_V']:.2f} V" if status["voltage_V"] > 0 else "",
             f"{status['current_A']:.1f} A" if math.isfinite(status["current_A"]) else "",
             f"{used:.0f} mAh used" if math.isfinite(used) and used >= 0 else "",
             f"{status['remaining_pct']:.0f} % left" if math.isfinite(status["remaining_pct"]) else ""]
    return ", ".join(p for p in parts if p) or NOT_REPORTED


def _number(value: float, fmt: str) -> str:
    return "—" if value is None or math.isnan(value) or math.isinf(value) else format(value, fmt)


class LinkPanel(QtWidgets.QGroupBox):
    def __init__(self, parent=None):
        super().__init__("Link", parent)
        self.headline = QtWidgets.QLabel("no source")
        self.headline.setStyleSheet(STYLES["idle"])
        self.values = {name: QtWidgets.QLabel("—") for name in (*FIELDS, *RADIO_FIELDS, BATTERY)}
        self.form = QtWidgets.QFormLayout(self)
        self.form.addRow(self.headline)
        for name, label in self.values.items():
            # As wide as its widest figure from the start (the side column's width is set when it is made).
            label.setMinimumWidth(label.fontMetrics().horizontalAdvance(WIDEST_VALUE) + 4)
            self.form.addRow(name, label)
        self._show_radio({})

    def _show_state(self, state: str, text: str) -> None:
        self.headline.setText(text)
        if self.headline.property("state") != state:  # a style sheet change restyles the widget
            self.headline.setProperty("state", state)
            self.headline.setStyleSheet(STYLES[state])

    def _show_radio(self, figures: dict[str, str]) -> None:
        for name in (*RADIO_FIELDS, BATTERY):
            self.form.setRowVisible(self.values[name], name in figures)
            self.values[name].setText(figures.get(name, "—"))

    def refresh(self, session: Session | None) -> None:
        if session is None or session.view.link is None:  # disconnected, or a file with no link in it
            self._show_state("idle", "no source" if session is None else "NO LINK (a log or dataset)")
            for label in self.values.values():
                label.setText("—")
            self._show_radio({})
            return
        self._show_radio(radio_figures(session))
        # A replay's link times are the recorded ones: measure "since" against the newest chunk.
        replay = session.source.is_replay
        now_ns = (session.view.link.last_chunk_ns or 0) if replay else time.monotonic_ns()
        f = link_figures(session, now_ns)
        self._show_state(*link_state(session, f))
        self.values["frames/s"].setText(_number(f["frames_per_s"], ".0f"))
        self.values["loss"].setText(f"{_number(f['loss_pct'], '.1f')} %  ({f['lost_total']} in all; "
                                    f"{_number(f['loss_now_pct'], '.1f')} % in the last second)")
        self.values["CRC failures"].setText(f"{_number(f['crc_per_s'], '.0f')}/s  ({f['crc_total']} in all)")
        self.values["bytes/s"].setText(_number(f["bytes_per_s"], ".0f"))
        self.values["since last frame"].setText(f"{_number(f['since_last_frame_s'] * 1e3, '.0f')} ms")
        self.values["latency p50 / p99"].setText(
            f"{_number(f['latency_p50_ms'], '.1f')} / {_number(f['latency_p99_ms'], '.1f')} ms")

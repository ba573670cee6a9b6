"""Flight modes by name, and the spans of a session's modes for the plots' time axis and the flight report.

Names are pymavlink's, so a link, a ``.tlog`` and a log of the same flight say the same word:

- ArduPilot numbers its modes per vehicle type (5 is LOITER on a copter, FBWA on a plane): MAVLink
  ``HEARTBEAT.custom_mode`` with ``HEARTBEAT.type``, and DataFlash ``MODE.ModeNum`` with the vehicle
  type DFReader reads from the log's firmware message, both through ``mavutil.mode_mapping_bynumber``;
- PX4 sends its main mode in ``custom_mode`` bits 16-23 and its sub mode in bits 24-31
  (``mavutil.interpret_px4_mode``); a ULog has ``vehicle_status.nav_state`` instead, which PX4's
  commander turns into that custom mode (``NAV_STATE_CUSTOM``, from PX4's ``px4_custom_mode.h``
  ``get_px4_custom_mode``), so it is named the same way (DESCEND is LAND, ORBIT is POSCTL there, as a
  ground station on the link shows them); a state pymavlink has no name for keeps PX4's.

Every maker says a mode or arming change as one ``vehicle_status`` event (``mode``, ``armed``: True,
False or None when the log never says) with its session time; ``mode_spans`` turns those into spans.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable

from pymavlink import mavutil

STATUS_KIND = "vehicle_status"  # the event kind of a mode or arming change

# PX4 vehicle_status.nav_state -> (PX4's name, custom main mode, custom sub mode); mavutil's PX4_CUSTOM_*.
_AUTO = mavutil.PX4_CUSTOM_MAIN_MODE_AUTO
NAV_STATE_CUSTOM = {
    0: ("MANUAL", mavutil.PX4_CUSTOM_MAIN_MODE_MANUAL, 0),
    1: ("ALTCTL", mavutil.PX4_CUSTOM_MAIN_MODE_ALTCTL, 0),
    2: ("POSCTL", mavutil.PX4_CUSTOM_MAIN_MODE_POSCTL, 0),
    3: ("AUTO_MISSION", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_MISSION),
    4: ("AUTO_LOITER", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_LOITER),
    5: ("AUTO_RTL", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_RTL),
    6: ("AUTO_RCRECOVER", _AUTO, 0),
    7: ("AUTO_RTGS", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_RTGS),
    8: ("AUTO_LANDENGFAIL", _AUTO, 0),
    9: ("AUTO_LANDGPSFAIL", _AUTO, 0),
    10: ("ACRO", mavutil.PX4_CUSTOM_MAIN_MODE_ACRO, 0),
    12: ("DESCEND", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_LAND),
    13: ("TERMINATION", mavutil.PX4_CUSTOM_MAIN_MODE_MANUAL, 0),
    14: ("OFFBOARD", mavutil.PX4_CUSTOM_MAIN_MODE_OFFBOARD, 0),
    15: ("STAB", mavutil.PX4_CUSTOM_MAIN_MODE_STABILIZED, 0),
    16: ("RATTITUDE", mavutil.PX4_CUSTOM_MAIN_MODE_RATTITUDE, 0),
    17: ("AUTO_TAKEOFF", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_TAKEOFF),
    18: ("AUTO_LAND", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_LAND),
    19: ("AUTO_FOLLOW_TARGET", _AUTO, mavutil.PX4_CUSTOM_SUB_MODE_AUTO_FOLLOW_TARGET),
    20: ("AUTO_PRECLAND", _AUTO, 0),
    21: ("ORBIT", mavutil.PX4_CUSTOM_MAIN_MODE_POSCTL, 0),
    22: ("AUTO_VTOL_TAKEOFF", _AUTO, 0),
}
PX4_ARMED_STATES = (2, 3)  # vehicle_status.arming_state ARMED (and ARMED_ERROR in PX4 before 1.9)


def ardupilot_mode(vehicle_type: int, number: int) -> str:
    """An ArduPilot mode number's name for a vehicle of MAV_TYPE ``vehicle_type``; ``Mode(n)`` if unknown."""
    names = mavutil.mode_mapping_bynumber(vehicle_type) or {}
    return names.get(int(number), f"Mode({int(number)})")


def px4_nav_state_mode(nav_state: int) -> str:
    """A PX4 ``vehicle_status.nav_state`` by the name a MAVLink link gives the custom mode PX4 sends for it."""
    known = NAV_STATE_CUSTOM.get(int(nav_state))
    if known is None:
        return f"NavState({int(nav_state)})"
    px4_name, main, sub = known
    name = mavutil.interpret_px4_mode(0, (main << 16) | (sub << 24))
    return px4_name if name == "UNKNOWN" else name


def status_event(mode: str, armed: bool | None, **times) -> dict:
    """A mode or arming change; ``times``: the link's ``t_host_ns`` and ``session_time_s``, or none (a log's
    reader: the session places its events)."""
    return {**times, "kind": STATUS_KIND, "mode": mode, "armed": armed}


@dataclasses.dataclass(frozen=True)
class ModeSpan:
    start_s: float  # session time, s
    end_s: float
    mode: str
    armed: bool | None  # None: the session never said


def event_time_s(event: dict) -> float:
    """An event's session time: its ``session_time_s`` when known, else ``t_s`` (from the first byte), else 0."""
    for key in ("session_time_s", "t_s"):
        value = event.get(key)
        if value is not None and math.isfinite(value):
            return float(value)
    return 0.0


def mode_spans(events: Iterable[dict], end_s: float) -> list[ModeSpan]:
    """The session's flight-mode spans, in time order: each ``vehicle_status`` event of ``events``
    (``SessionData.events``, or a window's ``view.events``) starts one, which lasts until the next
    change or ``end_s`` (the session's last time, e.g. ``SessionData.time_s[-1]``). A change of arming
    alone starts a new span with the same mode; events before the first ``vehicle_status`` have no span.
    Empty when the session never reported a mode (the project's own aircraft, a dataset)."""
    changes = sorted(((event_time_s(e), e["mode"], e.get("armed")) for e in events if e.get("kind") == STATUS_KIND),
                     key=lambda change: change[0])
    spans: list[ModeSpan] = []
    for t_s, mode, armed in changes:
        if spans and (spans[-1].mode, spans[-1].armed) == (mode, armed):
            continue
        if spans:
            spans[-1] = dataclasses.replace(spans[-1], end_s=t_s)
        spans.append(ModeSpan(t_s, t_s, mode, armed))
    if spans:
        spans[-1] = dataclasses.replace(spans[-1], end_s=max(end_s, spans[-1].start_s))
    return spans
